"""Data-generation shards on the offline pools: the same actor pattern as ``mani offline``, over objects.

A shard job is a row ``{"id": "shard-00003", "index": 3}``; `ShardWorker` (loaded once per process or Ray actor:
it loads the data set's hands) runs `research.data.generate.run_shard` into a scratch directory and answers
``{"id", "index", "result": str (JSON of the `ShardResult`), "files": bytes (msgpack of {file name: bytes})}``.
The driver writes the files into the data set and records the shard in its manifest, so the cluster needs no
file system shared with the driver. `ray_runner` is the `ShardRunner` that ``mani-lab data generate --ray`` hands
to `research.data.generate.generate`.
"""

from __future__ import annotations

import json
import os
import tempfile
from collections.abc import Iterator
from dataclasses import asdict, dataclass
from pathlib import Path

from manifoundation.contract.codec import pack, unpack
from manifoundation.server.offline.pool import BatchFn, Row
from research.data.generate import DataConfig, ShardJob, ShardResult, ShardRunner, available_hands, run_shard


@dataclass(frozen=True)
class ShardWorker:
    """A picklable `WorkerFactory` for the shards of one data set's configuration."""

    cfg: DataConfig

    def __call__(self) -> BatchFn:
        from manifoundation.core.robots import get_hand

        for name in available_hands(self.cfg.hands) + available_hands(self.cfg.held_out_hands):
            get_hand(name)  # loaded once per actor (the registry keeps them)
        return _ShardBatch(self.cfg)


class _ShardBatch:
    def __init__(self, cfg: DataConfig) -> None:
        self.cfg = cfg

    def __call__(self, rows: list[Row]) -> list[Row]:
        return [self._one(int(row["index"])) for row in rows]

    def _one(self, index: int) -> Row:
        with tempfile.TemporaryDirectory(prefix="mani-shard-") as scratch:
            result = run_shard(self.cfg, index, scratch)
            files = {p.name: p.read_bytes() for p in sorted(Path(scratch).iterdir()) if ".tmp" not in p.name}
        return {"id": f"shard-{index:05d}", "index": index, "result": json.dumps(asdict(result)),
                "files": pack(files)}  # fmt: skip


def write_shard(row: Row, out_dir: Path) -> ShardResult:
    """Write an answer row's files into ``out_dir`` (each atomically, the shard before its grasp-set cache so the
    cache stays newer) and return its `ShardResult`."""
    packed = row["files"]
    if not isinstance(packed, bytes):
        raise TypeError(f"a shard's files are msgpack bytes, not {type(packed).__name__}")
    files: dict[str, bytes] = unpack(packed)
    for name in sorted(files, key=lambda n: n.endswith(".sets.npz")):
        tmp = out_dir / f".{name}.{os.getpid()}.tmp"
        tmp.write_bytes(files[name])
        os.replace(tmp, out_dir / name)
    return ShardResult(**json.loads(str(row["result"])))


def ray_runner(address: str, workers: int) -> ShardRunner:
    """A `ShardRunner` on the Ray cluster at ``address`` with ``workers`` actors (one shard a task)."""

    def run(jobs: list[ShardJob]) -> Iterator[ShardResult]:
        from manifoundation.server.offline.ray_pool import run_ray

        if not jobs:
            return
        cfg, out_dir = jobs[0][0], Path(jobs[0][2])
        rows: list[Row] = [{"id": f"shard-{k:05d}", "index": k} for _, k, _ in jobs]
        for batch in run_ray(rows, ShardWorker(cfg), address=address, workers=workers, batch_size=1):
            for row in batch:
                yield write_shard(row, out_dir)

    return run
