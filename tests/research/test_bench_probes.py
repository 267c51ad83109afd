"""The raw-socket probes of `mani-lab bench faults` measure what they say: 429s timed to the status line (with and
without ``Expect: 100-continue``), and slow heads counted as closed by the server."""

from __future__ import annotations

import asyncio
import json
import threading
import time

import uvicorn

from manifoundation.server.api.app import create_app
from manifoundation.server.api.cli import uvicorn_config
from manifoundation.server.api.settings import Settings
from manifoundation.server.queue import create_queue
from research.bench.probes import raw_posts, slow_headers
from tests.api.helpers import request_body
from tests.api.server import free_port


def test_probes_against_a_full_queue_and_a_short_head_bound() -> None:
    settings = Settings(rate_limit_per_s=0, header_timeout=0.5, host="127.0.0.1", port=free_port())
    queue = create_queue(None, redis_url=None, concurrency=0, max_queue=1)
    server = uvicorn.Server(uvicorn_config(create_app(settings, queue=queue), settings))
    thread = threading.Thread(target=server.run, daemon=True)
    thread.start()
    try:
        while not server.started:
            time.sleep(0.02)
        body = json.dumps(request_body("test_gripper")).encode()
        first = asyncio.run(raw_posts("127.0.0.1", settings.port, "/v1/jobs", body, 1))
        assert [s for s, _ in first] == [202]
        for expect in (False, True):
            answers = asyncio.run(raw_posts("127.0.0.1", settings.port, "/v1/jobs", body * 40, 5, expect=expect))
            assert [s for s, _ in answers] == [429] * 5 and all(0 < t < 5 for _, t in answers), answers
        closed, after = asyncio.run(slow_headers("127.0.0.1", settings.port, 3, 0.1, 5.0))
        assert closed == 3 and max(after) < 2.0, after
    finally:
        server.should_exit = True
        thread.join(30)
