"""`/v1/jobs`: list, get, cancel, and stream a job's progress (Server-Sent Events)."""

from __future__ import annotations

import asyncio
import time
from collections.abc import AsyncIterator

from fastapi import APIRouter, Query, Request
from starlette.responses import Response, StreamingResponse

from manifoundation.contract import JobList, JobPublic
from manifoundation.server.api.deps import Authorized, CallerDep, MetricsDep, QueueDep, SettingsDep
from manifoundation.server.api.negotiation import respond
from manifoundation.server.api.responses import READ_ERRORS
from manifoundation.server.api.services import services_of

router = APIRouter(prefix="/v1/jobs", tags=["jobs"], dependencies=[Authorized])

SSE_KEEPALIVE_S = 15.0
JOB_ID = r"^[A-Za-z0-9_\-:.]{1,128}$"


@router.get("", summary="Recent jobs, newest first", responses={200: {"model": JobList}, **READ_ERRORS})
async def list_jobs(
    request: Request, queue: QueueDep, caller: CallerDep, limit: int = Query(50, ge=1, le=500)
) -> Response:
    return respond(request, JobList(jobs=await queue.list_recent(limit=limit, owner=caller.scope)))


@router.get(
    "/{job_id}",
    summary="A job: state, stage, progress, timings, result or error",
    responses={200: {"model": JobPublic}, **READ_ERRORS},
)
async def get_job(request: Request, job_id: str, queue: QueueDep, metrics: MetricsDep, caller: CallerDep) -> Response:
    job = await queue.get(job_id, owner=caller.scope)
    metrics.observe_job(job)
    return respond(request, job)


@router.delete(
    "/{job_id}",
    summary="Cancel a queued or running job (no-op when it has ended)",
    responses={200: {"model": JobPublic}, **READ_ERRORS},
)
async def cancel_job(request: Request, job_id: str, queue: QueueDep, caller: CallerDep) -> Response:
    return respond(request, await queue.cancel(job_id, owner=caller.scope))


@router.get(
    "/{job_id}/events",
    summary="Progress as Server-Sent Events until the job ends",
    response_class=StreamingResponse,
    responses={
        200: {"content": {"text/event-stream": {}}, "description": "`progress` events, then one `end`"},
        **READ_ERRORS,
    },
)
async def job_events(
    request: Request, job_id: str, queue: QueueDep, settings: SettingsDep, caller: CallerDep
) -> StreamingResponse:
    """``event: progress`` with the job (no result) on every change, then ``event: end`` with the full job."""
    await queue.get(job_id, with_result=False, owner=caller.scope)  # 404 (unknown or another's) before the stream
    return StreamingResponse(
        _stream(request, queue, job_id, settings.sse_interval),
        media_type="text/event-stream",
        headers={"Cache-Control": "no-cache", "X-Accel-Buffering": "no"},
    )


def _event(name: str, job: JobPublic) -> bytes:
    return f"event: {name}\ndata: {job.model_dump_json(exclude_none=True)}\n\n".encode()


async def _stream(request: Request, queue: QueueDep, job_id: str, interval: float) -> AsyncIterator[bytes]:
    events = queue.events(job_id, interval=interval).__aiter__()
    pending: asyncio.Task[JobPublic] | None = None
    quiet_since = time.monotonic()
    try:
        while not services_of(request).shutting_down:
            pending = pending or asyncio.ensure_future(events.__anext__())
            done, _ = await asyncio.wait({pending}, timeout=1.0)  # wake up each second to notice a shutdown
            if not done:
                if time.monotonic() - quiet_since > SSE_KEEPALIVE_S:
                    quiet_since = time.monotonic()
                    yield b": keep-alive\n\n"
                continue
            try:
                job = pending.result()
            except StopAsyncIteration:
                break
            pending = None
            if job.state.terminal:
                break
            quiet_since = time.monotonic()
            yield _event("progress", job)
        yield _event("end", await queue.get(job_id))
    finally:
        if pending is not None and not pending.done():
            pending.cancel()
