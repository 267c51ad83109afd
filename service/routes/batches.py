"""`/v1/batches`: many requests in one call, then counts by state and pages of items."""

from __future__ import annotations

import asyncio
import logging
import time

from fastapi import APIRouter, Query, Request
from starlette.responses import Response

from clients.schemas import BatchCreate, BatchItem, BatchPublic, FieldError, JobPublic, JobState
from service.deps import Authorized, CallerDep, MetricsDep, QueueDep, RequestIdDep, RobotsDep, SettingsDep
from service.errors import InvalidInput
from service.negotiation import body_openapi, read_model, respond
from service.responses import ERRORS, READ_ERRORS
from service.routes.synthesis import admit

router = APIRouter(prefix="/v1/batches", tags=["batches"], dependencies=[Authorized])
log = logging.getLogger("service.batches")


@router.post(
    "",
    status_code=202,
    summary="Submit up to 1000 requests at once",
    openapi_extra=body_openapi("BatchCreate", "`{requests: [SynthesisRequest, ...]}` (1 to 1000 of them)."),
    responses={202: {"model": BatchPublic}, **ERRORS},
)
async def create_batch(
    request: Request,
    queue: QueueDep,
    robots: RobotsDep,
    metrics: MetricsDep,
    settings: SettingsDep,
    request_id: RequestIdDep,
    caller: CallerDep,
) -> Response:
    """All or none are enqueued (owned by the caller); 202 with the batch and its first page of job ids."""
    await admit(queue)
    body = await read_model(request, BatchCreate, settings.max_body_bytes)
    if len(body.requests) > settings.max_batch_size:
        raise InvalidInput(f"requests: {len(body.requests)} requests, at most {settings.max_batch_size} per batch")
    if queue.capacity is not None and len(body.requests) > queue.capacity:
        raise InvalidInput(
            f"requests: {len(body.requests)} requests can never fit: the queue holds at most {queue.capacity} jobs"
            " (MANI_MAX_QUEUE); split the batch",
            detail=[FieldError(field="requests", problem=f"more than the queue's capacity of {queue.capacity}")],
        )
    for index, item in enumerate(body.requests):
        await robots.check(item, caller.tenant, field=f"requests.{index}.robot.name")
    batch_id = await queue.create_batch(body.requests, request_id=request_id, owner=caller.tenant)
    log.info("batch submitted", extra={"batch_id": batch_id, "jobs": len(body.requests), "request_id": request_id})
    metrics.batch_size.observe(len(body.requests))
    metrics.jobs_submitted.labels(kind="batch").inc(len(body.requests))
    job_ids = await queue.batch_job_ids(batch_id, owner=caller.tenant)
    limit = min(100, len(job_ids))
    items = [BatchItem(index=i, job_id=j, state=JobState.QUEUED) for i, j in enumerate(job_ids[:limit])]
    batch = BatchPublic(
        id=batch_id,
        total=len(job_ids),
        counts={JobState.QUEUED: len(job_ids)},
        done=False,
        items=items,
        offset=0,
        limit=limit,
        created_at=time.time(),
    )
    url = str(request.url_for("get_batch", batch_id=batch_id))
    return respond(request, batch, status=202, headers={"Location": url})


@router.get(
    "/{batch_id}",
    summary="Counts by state and one page of items (results when done)",
    responses={200: {"model": BatchPublic}, **READ_ERRORS},
)
async def get_batch(
    request: Request,
    batch_id: str,
    queue: QueueDep,
    settings: SettingsDep,
    caller: CallerDep,
    offset: int = Query(0, ge=0),
    limit: int = Query(100, ge=1, le=1000),
) -> Response:
    job_ids = await queue.batch_job_ids(batch_id, owner=caller.scope)
    limit = min(limit, settings.batch_page_max)
    states = await asyncio.gather(*(queue.get(j, with_result=False) for j in job_ids))
    page_ids = job_ids[offset : offset + limit]
    page = await asyncio.gather(*(queue.get(j) for j in page_ids))
    counts: dict[JobState, int] = {}
    for job in states:
        counts[job.state] = counts.get(job.state, 0) + 1
    batch = BatchPublic(
        id=batch_id,
        total=len(job_ids),
        counts=counts,
        done=all(j.state.terminal for j in states),
        items=[_item(offset + i, job) for i, job in enumerate(page)],
        offset=offset,
        limit=limit,
        created_at=min((j.created_at for j in states), default=time.time()),
    )
    return respond(request, batch)


def _item(index: int, job: JobPublic) -> BatchItem:
    return BatchItem(index=index, job_id=job.id, state=job.state, result=job.result, error=job.error)
