"""The shard worker of `mani-lab data generate --ray`, without Ray: its answer row, written by the driver, is the
shard `run_shard` writes itself (arrays equal), and the generator records it in the manifest."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from manifoundation.server.offline.pool import run_local
from research.data.generate import DataConfig, generate, run_shard
from research.offline.shards import ShardWorker, write_shard

CFG = DataConfig(objects=2, objects_per_shard=1, hands=("panda_gripper",), held_out_hands=(), palms=6,
                 grasps_per_job=2, examples_per_grasp=2, num_points=256, test_fraction=0.0,
                 kinds=("box", "sphere"))  # fmt: skip


def test_an_answer_row_writes_the_shard_run_shard_writes(tmp_path: Path) -> None:
    (tmp_path / "direct").mkdir()
    (tmp_path / "rows").mkdir()
    direct = run_shard(CFG, 0, str(tmp_path / "direct"))  # a box with 4 examples
    [[row]] = list(run_local([{"id": "shard-00000", "index": 0}], ShardWorker(CFG)))
    via_row = write_shard(row, tmp_path / "rows")
    assert (via_row.index, via_row.file, via_row.examples, via_row.counts) == (
        direct.index, direct.file, direct.examples, direct.counts)  # fmt: skip
    names = sorted(p.name for p in (tmp_path / "direct").iterdir())
    assert names == sorted(p.name for p in (tmp_path / "rows").iterdir()) and direct.examples > 0
    for name in names:
        a, b = np.load(tmp_path / "direct" / name), np.load(tmp_path / "rows" / name)
        assert a.files == b.files
        for key in a.files:
            np.testing.assert_array_equal(a[key], b[key], err_msg=f"{name}:{key}")  # NaN equals NaN here


def test_generate_records_what_a_runner_yields_and_lists_what_it_lost(tmp_path: Path) -> None:
    def runner(jobs: list[tuple[DataConfig, int, str]]):  # type: ignore[no-untyped-def]
        rows = [{"id": f"shard-{k}", "index": k} for _, k, _ in jobs if k == 0]  # shard 1 "lost"
        for batch in run_local(rows, ShardWorker(CFG)):  # type: ignore[arg-type]
            yield from (write_shard(row, tmp_path) for row in batch)

    manifest = generate(CFG, tmp_path, progress=False, runner=runner)
    assert list(manifest["shards"]) == ["0"] and manifest["lost_shards"] == [1]
