"""`mani-lab bench service --rss`: rows of API and worker RSS as the requests are answered."""

from __future__ import annotations

import asyncio
import json
import os
import subprocess
import sys

from manifoundation.server.api.app import create_app
from manifoundation.server.api.settings import Settings
from research.bench.rss import HEADER, format_row, rss_over_requests, worker_pids
from tests.api.fakes import FakeQueue
from tests.api.helpers import request_body
from tests.api.server import serving


def test_rss_rows_over_requests() -> None:
    body = json.dumps(request_body("fake_hand")).encode()
    seen: list[int] = []
    # a stand-in for an embedded worker: a child of this process whose command line names
    # `manifoundation.server.worker.child`
    child = "manifoundation.server.worker.child"
    worker = subprocess.Popen([sys.executable, "-c", "import sys; sys.stdin.read()", child],
                              stdin=subprocess.PIPE)  # fmt: skip
    try:
        with serving(create_app(Settings(rate_limit_per_s=0), queue=FakeQueue())) as base:
            run = rss_over_requests(base, {"Content-Type": "application/json"}, body, os.getpid(), total=6,
                                    clients=2, rows=3, on_row=lambda row: seen.append(row["requests"]))  # fmt: skip
            table = asyncio.run(run)
        assert worker.pid in worker_pids(os.getpid())  # (other tests' embedded workers may be children too)
    finally:
        worker.communicate(b"", timeout=30)
    assert [r["requests"] for r in table] == seen == [0, 2, 4, 6]
    assert all(r["failed"] == 0 and r["api_mb"] > 0 and r["workers_mb"][0] > 0 for r in table), table
    # the anonymous part of a worker's memory is a part of its RSS
    assert all(0 < r["workers_anon_mb"][0] <= r["workers_mb"][0] for r in table), table
    assert format_row(table[-1]).count("|") == HEADER.splitlines()[0].count("|")
