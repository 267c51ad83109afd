"""The API under faults of what it waits on: a hung Redis (SIGSTOP) must give 503s within seconds."""

from __future__ import annotations

import time
from pathlib import Path

import httpx

from service.app import create_app
from service.settings import Settings
from tests.workers.redis_server import redis_server
from workers.queue import create_queue

from .helpers import request_body
from .server import serving


def test_hung_redis_gives_503_within_seconds(tmp_path: Path) -> None:
    with redis_server(tmp_path) as server:
        queue = create_queue(server.url, queue_prefix="mani:", redis_timeout=0.5)
        app = create_app(Settings(rate_limit_per_s=0, robots_cache_s=0), queue=queue)
        with serving(app) as base, httpx.Client(base_url=base, timeout=30) as http:
            server.pause()
            try:
                for method, path, body in (
                    ("GET", "/readyz", None),
                    ("POST", "/v1/jobs", request_body("test_gripper")),
                    ("GET", "/v1/jobs", None),
                    ("GET", "/v1/robots", None),
                    ("GET", "/v1/jobs/" + "0" * 32, None),
                ):
                    t0 = time.monotonic()
                    answer = http.request(method, path, json=body)
                    elapsed = time.monotonic() - t0
                    assert answer.status_code == 503, (path, answer.text)
                    assert elapsed < 3.0, (path, elapsed)
                    assert path == "/readyz" or answer.headers["retry-after"]
            finally:
                server.resume()
            assert http.get("/v1/jobs").status_code == 200
