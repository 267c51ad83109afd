"""Following one HTTP request to the worker that ran its job, on the real backends (embedded; Redis when
reachable): the ``X-Request-ID`` the service answers is kept in the job's record and is on the worker's log lines
for the job, next to the job id."""

from __future__ import annotations

import contextlib
import json
import time
from collections.abc import Iterator
from typing import Any

import httpx
import pytest
import redis

from manifoundation.server.api.app import create_app
from manifoundation.server.api.settings import Settings
from manifoundation.server.queue import JobQueue
from manifoundation.server.queue.embedded import EmbeddedQueue
from manifoundation.server.queue.redis import RedisQueue

from .helpers import request_body
from .server import serving
from .workers import start_queue_and_workers

HAND = "test_gripper"


class Served:
    def __init__(self, queue: JobQueue, http: httpx.Client, capfd: pytest.CaptureFixture[str]) -> None:
        self.queue, self.http, self.capfd = queue, http, capfd
        self.text = ""

    def record_request_id(self, job_id: str) -> str | None:
        """The request id in the job's record, as the backend keeps it."""
        if isinstance(self.queue, EmbeddedQueue):
            return self.queue._jobs[job_id].request_id
        assert isinstance(self.queue, RedisQueue) and self.queue.settings.redis_url
        with redis.Redis.from_url(self.queue.settings.redis_url) as client:
            value = client.hget(self.queue.keys.job(job_id), "request_id")
        return None if value is None else value.decode()  # type: ignore[union-attr]

    def worker_lines(self, job_ids: set[str], timeout: float = 20) -> list[dict[str, Any]]:
        """The worker's JSON log lines of these jobs, once each has its "job finished" line."""
        deadline = time.monotonic() + timeout
        while True:
            self.text += self.capfd.readouterr().err
            whole = self.text[: self.text.rfind("\n") + 1]
            lines = [json.loads(line) for line in whole.splitlines() if line.startswith("{")]
            # the worker's lines name their worker; the service's own lines about a job do not
            mine = [e for e in lines if e.get("job_id") in job_ids and "worker" in e]
            if {e["job_id"] for e in mine if e.get("msg") == "job finished"} == job_ids:
                return mine
            assert time.monotonic() < deadline, f"no 'job finished' line for every job in:\n{self.text[-3000:]}"
            time.sleep(0.05)


@pytest.fixture(params=["embedded", pytest.param("redis", marks=pytest.mark.slow)])
def backend(request: pytest.FixtureRequest) -> pytest.FixtureRequest:
    return request


@contextlib.contextmanager
def serve(backend: pytest.FixtureRequest, capfd: pytest.CaptureFixture[str]) -> Iterator[Served]:
    """The service on ``backend`` with one worker. Started inside the test itself: a process spawned during a
    fixture's setup keeps writing where capfd no longer reads once the test runs."""
    with start_queue_and_workers(backend, stage_seconds=0.01, worker_logs=True) as queue:
        app = create_app(Settings(rate_limit_per_s=0, sync_wait_max=20), queue=queue)
        with serving(app) as base, httpx.Client(base_url=base, timeout=60) as http:
            deadline = time.monotonic() + 120
            while http.get("/readyz").status_code != 200:
                assert time.monotonic() < deadline, "no worker became ready"
                time.sleep(0.1)
            yield Served(queue, http, capfd)


def test_request_id_reaches_the_job_record_and_the_worker_logs(
    backend: pytest.FixtureRequest, capfd: pytest.CaptureFixture[str]
) -> None:
    with serve(backend, capfd) as served:
        sync = served.http.post("/v1/synthesize", json=request_body(HAND), headers={"X-Request-ID": "abc-123"})
        assert sync.status_code == 200 and sync.headers["x-request-id"] == "abc-123", sync.text
        job_id = sync.headers["x-job-id"]
        created = served.http.post("/v1/jobs", json=request_body(HAND), headers={"X-Request-ID": "abc-124"})
        async_id = created.json()["id"]
        batch = served.http.post(
            "/v1/batches", json={"requests": [request_body(HAND)] * 2}, headers={"X-Request-ID": "abc-125"}
        )
        batch_ids = [item["job_id"] for item in batch.json()["items"]]
        expected = {job_id: "abc-123", async_id: "abc-124", **dict.fromkeys(batch_ids, "abc-125")}
        assert {i: served.record_request_id(i) for i in expected} == expected
        lines = served.worker_lines(set(expected))
        for entry in lines:
            assert entry.get("request_id") == expected[entry["job_id"]], entry
        finished = next(e for e in lines if e["job_id"] == job_id and e["msg"] == "job finished")
        assert finished["request_id"] == "abc-123" and finished["worker"]
        # the wire contract is unchanged: the request id stays internal
        assert "request_id" not in served.http.get(f"/v1/jobs/{job_id}").json()
