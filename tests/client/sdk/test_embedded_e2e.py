"""The SDK against the whole stack: the real app under uvicorn, the embedded queue and spawned worker processes.

The workers run `research.staged_pipeline.StagedPipeline` (real stage sequence and timings, no science), so these tests
follow real progress events, cancellation mid-run and batches through real processes in a few seconds. When the
science pipeline is installed, ``test_direct_grasp_with_a_built_in_hand`` also runs a real synthesis
(``method="direct_grasp"`` needs no trained weights).
"""

from __future__ import annotations

import contextlib
import socket
import threading
import time
from collections.abc import Iterator
from typing import Any

import numpy as np
import pytest
import uvicorn

from manifoundation.contract import JobState, Stage
from manifoundation.sdk import Client, JobFailed, make_request

HAND = "test_gripper"


def _free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return int(sock.getsockname()[1])


@contextlib.contextmanager
def stack(pipeline: str, options: dict[str, Any], concurrency: int = 1, ready_timeout: float = 60.0) -> Iterator[str]:
    """App + embedded queue (``concurrency`` worker processes running ``pipeline``) on a free port."""
    from manifoundation.server.api.app import create_app
    from manifoundation.server.api.settings import Settings
    from manifoundation.server.queue import create_queue

    queue = create_queue(None, concurrency=concurrency, pipeline=pipeline, pipeline_options=options)
    settings = Settings(log_level="WARNING", sync_wait_max=1.0, rate_limit_per_s=0, sse_interval=0.02)
    app = create_app(settings, queue=queue)
    port = _free_port()
    server = uvicorn.Server(uvicorn.Config(app, host="127.0.0.1", port=port, log_config=None, lifespan="on"))
    thread = threading.Thread(target=server.run, daemon=True)
    thread.start()
    url = f"http://127.0.0.1:{port}"
    try:
        deadline = time.monotonic() + ready_timeout
        while not server.started:
            assert thread.is_alive() and time.monotonic() < deadline, "uvicorn did not start"
            time.sleep(0.05)
        with Client(url, retries=0) as client:  # workers up (a model is not needed for every method)
            while (ready := client.ready()).workers < concurrency:
                if time.monotonic() > deadline:
                    raise AssertionError(f"workers not up in {ready_timeout:g} s: {ready.detail}")
                time.sleep(0.1)
        yield url
    finally:
        server.should_exit = True
        thread.join(timeout=60)


def _points(n: int = 128) -> np.ndarray:
    rng = np.random.default_rng(0)
    normals = rng.normal(size=(n, 3))
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    return np.hstack([normals * 0.04, normals])


@pytest.fixture(scope="module")
def url() -> Iterator[str]:
    options = {"stage_seconds": 0.05, "iterations": 4, "fail_seed": 13}
    with stack("research.staged_pipeline:StagedPipeline", options) as base:
        yield base


def test_progress_events_walk_the_real_stages(url: str) -> None:
    with Client(url, poll_interval=0.05) as client:
        job = client.submit(_points(), "force_closure", HAND, seed=1)
        events = list(job.events(timeout=30))
        assert events[-1].state is JobState.SUCCEEDED and events[-1].result is not None
        stages = [e.progress.stage for e in events[:-1]]
        order = [Stage.QUEUED, Stage.NETWORK, Stage.INITIALISATION, Stage.REFINEMENT, Stage.VERIFICATION]
        seen = [s for s in order if s in stages]
        assert Stage.REFINEMENT in seen and seen == sorted(seen, key=order.index)
        assert job.wait(10).model_version == "staged-test"
        assert "refinement" in job.status().timings or job.status().timings


def test_synthesize_sync_and_failure(url: str) -> None:
    with Client(url, poll_interval=0.05) as client:
        result = client.synthesize(_points(), "force_closure", HAND, seed=2, timeout=30)
        assert result.hand == HAND and result.timings
        with pytest.raises(JobFailed) as info:  # the job ran and failed: its error, not an HTTP error
            client.synthesize(_points(), "force_closure", HAND, seed=13, timeout=30)
        assert info.value.state is JobState.FAILED and info.value.error is not None
        assert "injected failure" in info.value.error.error
        assert client.job(info.value.job_id).status().state is JobState.FAILED


def test_cancel_mid_run(url: str) -> None:
    with Client(url, poll_interval=0.02) as client:
        job = client.submit(make_request(_points(), "force_closure", HAND, seed=3, max_iterations=200))
        for event in job.events(timeout=30):
            if event.state is JobState.RUNNING:
                job.cancel()
                break
        with pytest.raises(JobFailed) as info:
            job.wait(30)
        assert info.value.state is JobState.CANCELLED


def test_batch_through_worker_processes(url: str) -> None:
    with Client(url, poll_interval=0.05) as client:
        requests = [make_request(_points(), "force_closure", HAND, seed=100 + i) for i in range(6)]
        batch = client.submit_batch(requests)
        batch.page_size = 4
        seen: list[int] = []
        items = batch.wait(timeout=60, progress=lambda item: seen.append(item.index))
        assert [i.index for i in items] == list(range(6)) and sorted(seen) == list(range(6))
        assert all(i.state is JobState.SUCCEEDED for i in items)
        robots = [r.name for r in client.robots()]
        assert HAND in robots


@pytest.mark.slow
@pytest.mark.timeout(900)
def test_direct_grasp_with_a_built_in_hand() -> None:
    from pathlib import Path

    from manifoundation.sdk import delta_pose, object_from_file

    box = object_from_file(Path(__file__).resolve().parents[3] / "examples" / "data" / "box.npz")
    with (
        stack("manifoundation.server.worker.models_pipeline:ModelsPipeline", {}, ready_timeout=600) as base,
        Client(base) as client,
    ):
        result = client.synthesize(box, delta_pose([0, 0, 0.05]), "leap", method="direct_grasp", timeout=120)
        best = result.best
        assert best is not None and best.contact_points.shape[1] == 3
        assert best.joint_values.shape == (len(best.joint_names),)


@pytest.mark.slow
def test_example_scripts_run(tmp_path: Any) -> None:
    """The example scripts as a user runs them (subprocesses), against a fast staged stack (~15 s)."""
    import os
    from pathlib import Path

    examples = Path(__file__).resolve().parents[3] / "examples"
    with stack("research.staged_pipeline:StagedPipeline", {"stage_seconds": 0.0}, concurrency=2) as url:
        _run_examples(examples, {**os.environ, "MANI_URL": url}, tmp_path)


def _run_examples(examples: Any, env: dict[str, str], tmp_path: Any) -> None:
    import subprocess
    import sys

    def run(*argv: str) -> subprocess.CompletedProcess[str]:
        return subprocess.run([sys.executable, *argv], env=env, cwd=tmp_path, capture_output=True, text=True,
                              timeout=120)  # fmt: skip

    batch = run(str(examples / "batch_100.py"), "--hand", HAND, "--out", "results.jsonl")
    assert "batch " in batch.stdout and "100 requests" in batch.stdout, batch.stderr
    assert len((tmp_path / "results.jsonl").read_text().splitlines()) == 100
    hand = run(str(examples / "register_hand.py"))
    assert "registered my_two_finger: 4 joints" in hand.stdout, hand.stderr
    # the staged test pipeline returns no proposals: the scripts say so and exit 1 instead of crashing
    single = run(str(examples / "sync_call.py"), "--hand", HAND)
    assert single.returncode == 1 and "no hand pose" in single.stdout, single.stderr
