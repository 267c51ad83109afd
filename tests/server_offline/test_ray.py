"""`mani offline --ray` on a two-node local Ray cluster: the same results as the local path, no request lost when
one node's actors are killed mid-run, and a rerun after the driver itself was killed runs only what is missing."""

from __future__ import annotations

import os
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import TYPE_CHECKING

import pytest

from manifoundation.server.offline.batch import BatchSummary, run_batch
from manifoundation.server.offline.synthesis import SynthesisWorker
from tests.ray_cluster import LOOPBACK, kill_workers, two_nodes

from .requests import STAGED, results, write_requests

if TYPE_CHECKING:
    from ray.cluster_utils import Cluster

pytestmark = pytest.mark.slow
ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def cluster() -> Iterator[Cluster]:
    with two_nodes() as c:
        yield c


def _answered(out: Path) -> int:
    return len(list(out.glob("*.msgpack")))


def _wait_for(out: Path, count: int, alive: threading.Thread | subprocess.Popen[bytes], limit: float = 90) -> None:
    t0 = time.monotonic()
    running = alive.is_alive if isinstance(alive, threading.Thread) else lambda: alive.poll() is None
    while _answered(out) < count and running() and time.monotonic() - t0 < limit:
        time.sleep(0.1)
    assert _answered(out) >= count, f"only {_answered(out)} answers came"


def test_200_requests_equal_the_local_path_though_a_node_loses_its_actors(cluster: Cluster, tmp_path: Path) -> None:
    requests = tmp_path / "requests"
    write_requests(requests, 200, jsonl_from=150)
    run_batch(requests, tmp_path / "local", SynthesisWorker(STAGED), progress=False)
    slow = SynthesisWorker(STAGED, {"stage_seconds": 0.01})  # ~10 s of work: time to kill actors in the middle
    done: list[BatchSummary] = []
    run = threading.Thread(target=lambda: done.append(run_batch(
        requests, tmp_path / "ray", slow, ray_address=cluster.address, workers=2, progress=False)))  # fmt: skip
    run.start()
    _wait_for(tmp_path / "ray", 40, run)
    assert kill_workers(cluster), "no actor ran on the second node"
    run.join(timeout=120)
    assert done and done[0].answered == 200 and done[0].counts == {"succeeded": 200}
    assert results(tmp_path / "ray") == results(tmp_path / "local")


def test_a_rerun_after_the_driver_was_killed_runs_only_what_is_missing(cluster: Cluster, tmp_path: Path) -> None:
    requests, out = tmp_path / "requests", tmp_path / "out"
    write_requests(requests, 200, jsonl_from=100)
    argv = [sys.executable, "-m", "manifoundation.server.commands.offline", str(requests), "--out", str(out),
            "--ray", cluster.address, "--workers", "2", "--pipeline", STAGED,
            "--pipeline-options", '{"stage_seconds": 0.02}', "--no-progress"]  # fmt: skip
    env = os.environ | LOOPBACK | {"PYTHONPATH": str(ROOT)}
    driver = subprocess.Popen(argv, cwd=ROOT, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        _wait_for(out, 50, driver)
    finally:
        driver.kill()
        driver.wait()
    before = _answered(out)
    assert 50 <= before < 200
    summary = run_batch(requests, out, SynthesisWorker(STAGED), ray_address=cluster.address, workers=2,
                        progress=False)  # fmt: skip
    assert (summary.skipped, summary.ran, summary.answered) == (before, 200 - before, 200 - before)
    assert summary.counts == {"succeeded": 200}
    run_batch(requests, tmp_path / "local", SynthesisWorker(STAGED), progress=False)
    assert results(out) == results(tmp_path / "local")


def test_real_requests_give_the_local_answers_on_ray(cluster: Cluster, tmp_path: Path) -> None:
    requests = tmp_path / "requests"
    write_requests(requests, 4, jsonl_from=2)
    models = SynthesisWorker(options={"hands": ["panda_gripper"]})
    local = run_batch(requests, tmp_path / "local", models, progress=False)
    on_ray = run_batch(requests, tmp_path / "ray", models, ray_address=cluster.address, workers=2, batch_size=1,
                       progress=False)  # fmt: skip
    assert local.counts == on_ray.counts == {"succeeded": 4}
    assert results(tmp_path / "ray") == results(tmp_path / "local")


def test_a_request_that_kills_its_actor_every_time_fails_alone(cluster: Cluster, tmp_path: Path) -> None:
    requests = tmp_path / "requests"
    write_requests(requests, 12)
    crashing = SynthesisWorker(STAGED, {"crash_seed": 5})
    summary = run_batch(requests, tmp_path / "out", crashing, ray_address=cluster.address, workers=2, batch_size=4,
                        progress=False)  # fmt: skip
    assert summary.counts == {"succeeded": 11, "WorkerLost": 1}
    assert results(tmp_path / "out")["r0005"]["type"] == "WorkerLost"
