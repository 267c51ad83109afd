"""`POST /v1/synthesize` (wait, then 200 or 202) and `POST /v1/jobs` (202 at once)."""

from __future__ import annotations

import logging

from fastapi import APIRouter, Request
from starlette.responses import Response

from manifoundation.contract import ErrorBody, ErrorType, JobCreated, JobPublic, JobState, SynthesisResult
from manifoundation.server.api.deps import Authorized
from manifoundation.server.api.negotiation import body_openapi, respond
from manifoundation.server.api.responses import ERRORS
from manifoundation.server.api.services import services_of
from manifoundation.server.api.submission import Admitted, SubmitterDep, read_and_submit
from manifoundation.server.api.waiting import wait_for_job

router = APIRouter(prefix="/v1", tags=["synthesis"], dependencies=[Authorized])
log = logging.getLogger("manifoundation.server.api.synthesis")

# A failed job's error type → the status of a synchronous answer (anything else: 500, the worker's fault).


_WITHOUT_ERROR = {
    JobState.CANCELLED: ErrorType.CANCELLED,
    JobState.EXPIRED: ErrorType.DEADLINE_EXCEEDED,
    JobState.FAILED: ErrorType.INTERNAL_ERROR,
}
"""The error a terminal job without an error body answers with (no backend writes one; kept for safety)."""


def job_created(request: Request, job_id: str, job: JobPublic | None = None) -> Response:
    """202 with the job's URL (in the body and in Location)."""
    url = str(request.url_for("get_job", job_id=job_id))
    body = JobCreated(id=job_id, state=job.state if job else "queued", url=url)
    return respond(request, body, status=202, headers={"Location": url, "X-Job-ID": job_id})


@router.post(
    "/synthesize",
    dependencies=[Admitted],
    summary="Synthesise contacts, forces and a hand pose; wait for the answer",
    openapi_extra=body_openapi("SynthesisRequest"),
    responses={200: {"model": SynthesisResult}, 202: {"model": JobCreated}, **ERRORS},
)
async def synthesize(request: Request, submitter: SubmitterDep) -> Response:
    """Enqueue, wait up to ``options.timeout`` (capped by the server's ``sync_wait_max``): 200 with the result
    when it finishes in time, else 202 with the job's URL. The job's deadline is ``options.timeout`` from now."""
    body, job_id = await read_and_submit(request, submitter, "sync", deadline_from_timeout=True)
    queue, metrics = submitter.queue, submitter.metrics
    wait = min(body.options.timeout, submitter.settings.sync_wait_max)
    job = await wait_for_job(services_of(request), queue, job_id, wait, fetch_with="from another replica")
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


@router.post(
    "/jobs",
    status_code=202,
    dependencies=[Admitted],
    summary="Submit a job; poll it or stream its events",
    openapi_extra=body_openapi("SynthesisRequest"),
    responses={202: {"model": JobCreated}, **ERRORS},
)
async def create_job(request: Request, submitter: SubmitterDep) -> Response:
    """202 with the job's URL at once (no deadline: an asynchronous caller comes back for it)."""
    _, job_id = await read_and_submit(request, submitter, "async", deadline_from_timeout=False)
    return job_created(request, job_id)
