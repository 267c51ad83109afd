"""`POST /v1/synthesize` (wait, then 200 or 202) and `POST /v1/jobs` (202 at once)."""

from __future__ import annotations

import asyncio
import logging
import time

from fastapi import APIRouter, Request
from starlette.responses import Response

from clients.schemas import ErrorBody, ErrorType, JobCreated, JobPublic, JobState, SynthesisRequest, SynthesisResult
from service.deps import Authorized, CallerDep, MetricsDep, QueueDep, RequestIdDep, RobotsDep, SettingsDep
from service.errors import Unavailable
from service.negotiation import body_openapi, read_model, respond
from service.responses import ERRORS
from workers.queue import QueueFull

router = APIRouter(prefix="/v1", tags=["synthesis"], dependencies=[Authorized])
log = logging.getLogger("service.synthesis")

# A failed job's error type → the status of a synchronous answer (anything else: 500, the worker's fault).


_WITHOUT_ERROR = {
    JobState.CANCELLED: ErrorType.CANCELLED,
    JobState.EXPIRED: ErrorType.DEADLINE_EXCEEDED,
    JobState.FAILED: ErrorType.INTERNAL_ERROR,
}
"""The error a terminal job without an error body answers with (no backend writes one; kept for safety)."""


async def admit(queue: QueueDep, count: int = 1) -> None:
    """429 `QueueFull` before reading a body the queue has no room for (`submit` still decides, atomically)."""
    if not await queue.room(count):
        raise QueueFull("the queue is full; retry later", retry_after=1.0)


def job_created(request: Request, job_id: str, job: JobPublic | None = None) -> Response:
    """202 with the job's URL (in the body and in Location)."""
    url = str(request.url_for("get_job", job_id=job_id))
    body = JobCreated(id=job_id, state=job.state if job else "queued", url=url)
    return respond(request, body, status=202, headers={"Location": url, "X-Job-ID": job_id})


async def enqueue(
    request: Request,
    queue: QueueDep,
    robots: RobotsDep,
    metrics: MetricsDep,
    request_id: str,
    kind: str,
    settings: SettingsDep,
    deadline_from_timeout: bool,
    caller: CallerDep,
) -> tuple[SynthesisRequest, str]:
    """Refuse at once when the queue is full (before the body is read), read + validate the body, check the
    hand, submit (owned by the caller); returns the request and its id."""
    await admit(queue)
    body = await read_model(request, SynthesisRequest, settings.max_body_bytes)
    await robots.check(body, caller.tenant)
    deadline = time.time() + body.options.timeout if deadline_from_timeout else None
    (job_id,) = await queue.submit([body], deadline=deadline, request_id=request_id, owner=caller.tenant)
    request.state.job_id = job_id
    request.app.state.scenes.put(job_id, body)
    metrics.jobs_submitted.labels(kind=kind).inc()
    log.info("job submitted", extra={"job_id": job_id, "kind": kind, "request_id": request_id})
    return body, job_id


@router.post(
    "/synthesize",
    summary="Synthesise contacts, forces and a hand pose; wait for the answer",
    openapi_extra=body_openapi("SynthesisRequest"),
    responses={200: {"model": SynthesisResult}, 202: {"model": JobCreated}, **ERRORS},
)
async def synthesize(
    request: Request,
    queue: QueueDep,
    robots: RobotsDep,
    metrics: MetricsDep,
    settings: SettingsDep,
    request_id: RequestIdDep,
    caller: CallerDep,
) -> Response:
    """Enqueue, wait up to ``options.timeout`` (capped by the server's ``sync_wait_max``): 200 with the result
    when it finishes in time, else 202 with the job's URL. The job's deadline is ``options.timeout`` from now."""
    body, job_id = await enqueue(request, queue, robots, metrics, request_id, "sync", settings, True, caller)
    wait = min(body.options.timeout, settings.sync_wait_max)
    job = await wait_for(request, queue, job_id, wait)
    if not job.state.terminal:
        return job_created(request, job_id, job)
    metrics.observe_job(job)
    headers = {"X-Job-ID": job_id}
    if job.result is not None:
        return respond(request, job.result, headers=headers)
    error = job.error or ErrorBody.of(_WITHOUT_ERROR[job.state], f"job ended {job.state.value}")
    status = error.status
    if status >= 500:
        log.warning("job failed", extra={"job_id": job_id, "type": error.type, "error": error.error})
    return respond(request, error, status=status, headers=headers)


async def wait_for(request: Request, queue: QueueDep, job_id: str, timeout: float) -> JobPublic:
    """`queue.wait` in slices, giving up early (503) when the service starts shutting down."""
    end = time.monotonic() + timeout
    while True:
        left = end - time.monotonic()
        job = await queue.wait(job_id, max(0.0, min(left, 1.0)))
        if job.state.terminal or left <= 1.0:
            return job
        if getattr(request.app.state, "shutting_down", False):
            raise Unavailable(f"the service is shutting down; job {job_id} may be fetched from another replica")
        await asyncio.sleep(0)


@router.post(
    "/jobs",
    status_code=202,
    summary="Submit a job; poll it or stream its events",
    openapi_extra=body_openapi("SynthesisRequest"),
    responses={202: {"model": JobCreated}, **ERRORS},
)
async def create_job(
    request: Request,
    queue: QueueDep,
    robots: RobotsDep,
    metrics: MetricsDep,
    settings: SettingsDep,
    request_id: RequestIdDep,
    caller: CallerDep,
) -> Response:
    """202 with the job's URL at once (no deadline: an asynchronous caller comes back for it)."""
    _, job_id = await enqueue(request, queue, robots, metrics, request_id, "async", settings, False, caller)
    return job_created(request, job_id)
