"""A large batch over HTTP is packed into the embedded queue's spool by the body process that decodes it: the API
process never holds its arrays (issue 62, item 3), the payloads are the ones the API would have packed, and a
refused batch leaves no file behind."""

from __future__ import annotations

import json
import os
import shutil

import httpx

from manifoundation.contract import BatchCreate
from manifoundation.server.api.app import create_app
from manifoundation.server.api.bodies import SPOOL_BATCH
from manifoundation.server.api.settings import Settings
from manifoundation.server.queue import create_queue
from manifoundation.server.spool import payload_files, request_payload

from .helpers import request_body
from .server import serving


def test_a_large_batch_is_packed_into_the_spool_by_a_body_process() -> None:
    queue = create_queue(None, redis_url=None, concurrency=0, max_queue=4)  # no worker: the jobs wait, spooled
    app = create_app(Settings(rate_limit_per_s=0, parse_offload_bytes=1024), queue=queue)
    body = {"requests": [request_body("test_gripper", n=256, seed=seed) for seed in range(3)]}
    data = json.dumps(body).encode()
    seen: list[str] = []
    with serving(app) as base:
        bodies = app.state.services.bodies
        run = bodies.run

        async def counting(decoder, chunks, *args):  # type: ignore[no-untyped-def]
            seen.append(decoder)
            return await run(decoder, chunks, *args)

        bodies.run = counting
        headers = {"Content-Type": "application/json"}
        answer = httpx.post(f"{base}/v1/batches", content=data, headers=headers, timeout=60)
        assert answer.status_code == 202, answer.text
        assert seen == [SPOOL_BATCH]
        spool = queue.spool
        assert spool is not None
        expected = {request_payload(r) for r in BatchCreate.model_validate(body).requests}
        stored = set()
        for name in payload_files(spool):
            with open(os.path.join(spool, name), "rb") as spooled:
                stored.add(spooled.read())
        assert stored == expected and len(payload_files(spool)) == 3
        full = httpx.post(f"{base}/v1/batches", content=data, headers=headers, timeout=60)  # room for 1, not 3
        assert full.status_code == 429, full.text
        invalid = json.loads(data)
        invalid["requests"][2]["object"]["normals"] = invalid["requests"][2]["object"]["normals"][:-1]
        refused = httpx.post(f"{base}/v1/batches", json=invalid, timeout=60)
        assert refused.status_code == 422 and "requests.2.object" in refused.text, refused.text
        assert len(seen) == 3 and len(payload_files(spool)) == 3  # spooled, refused and removed; invalid: never written


def test_a_spool_that_cannot_be_written_is_503_not_the_callers_fault() -> None:
    """The spool's disk failing (here: its directory gone) is the service's problem: 503 with Retry-After, for a
    large batch (written by the body process) and a large single request (written by the queue) alike."""
    queue = create_queue(None, redis_url=None, concurrency=0, max_queue=10)
    app = create_app(Settings(rate_limit_per_s=0, parse_offload_bytes=1024), queue=queue)
    with serving(app) as base:
        assert queue.spool is not None
        shutil.rmtree(queue.spool)
        batch = {"requests": [request_body("test_gripper", n=256)] * 2}
        answer = httpx.post(f"{base}/v1/batches", json=batch, timeout=60)
        assert answer.status_code == 503 and "spool" in answer.json()["error"], answer.text
        assert "Retry-After" in answer.headers
        large = request_body("test_gripper", n=60_000)  # a 2.9 MB cloud: over SPOOL_BYTES
        single = httpx.post(f"{base}/v1/jobs", json=large, timeout=60)
        assert single.status_code == 503 and "spool" in single.json()["error"], single.text
        small = httpx.post(f"{base}/v1/jobs", json=request_body("test_gripper"), timeout=60)
        assert small.status_code == 202, small.text  # a payload kept in memory does not need the disk
