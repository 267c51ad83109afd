"""Waiting for a job to end, for every front end that answers when the job is done: HTTP's `POST /v1/synthesize`,
gRPC's `Synthesize` and MCP's ``wait_s``. One loop, so each notices the end, its time limit and a shutdown the same
way; how long each waits is its own (the request's ``options.timeout``, default the contract's
``DEFAULT_TIMEOUT_S``)."""

from __future__ import annotations

import asyncio
import time
from typing import TYPE_CHECKING

from manifoundation.contract import JobPublic
from manifoundation.server.api.errors import Unavailable
from manifoundation.server.queue import JobQueue

if TYPE_CHECKING:
    from manifoundation.server.api.services import AppServices

JOB_ID_HEADER = "X-Job-ID"
"""The header naming the job an answer is about (gRPC: its lower-case form, ``x-job-id``)."""

WAIT_SLICE_S = 1.0
"""The longest single `queue.wait`: a shutdown is noticed within this."""


async def wait_for_job(
    services: AppServices, queue: JobQueue, job_id: str, seconds: float, *, fetch_with: str
) -> JobPublic:
    """The job once it ended, or as it is after ``seconds``. `Unavailable` (503 / UNAVAILABLE) when the service
    starts shutting down meanwhile (``services.shutting_down``): the message tells the caller to fetch the job
    ``fetch_with`` (e.g. "with GetJob"); it carries the job's id as ``X-Job-ID`` (the HTTP header; gRPC's
    ``x-job-id`` trailing metadata), so a caller cut off by a restart fetches its job without parsing the text."""
    end = time.monotonic() + max(0.0, seconds)
    while True:
        left = end - time.monotonic()
        job: JobPublic = await queue.wait(job_id, max(0.0, min(left, WAIT_SLICE_S)))
        if job.state.terminal or left <= WAIT_SLICE_S:
            return job
        if services.shutting_down:
            cut_off = Unavailable(f"the service is shutting down; job {job_id} may be fetched {fetch_with}")
            cut_off.headers[JOB_ID_HEADER] = job_id
            raise cut_off
        await asyncio.sleep(0)
