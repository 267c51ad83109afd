"""`/v1/batches`: many requests in one call, then counts by state and pages of items."""

from __future__ import annotations

import logging

from fastapi import APIRouter, Query, Request
from starlette.responses import Response

from manifoundation.contract import BatchPublic
from manifoundation.server.api.batch_pages import batch_page
from manifoundation.server.api.deps import Authorized, CallerDep, QueueDep, SettingsDep
from manifoundation.server.api.negotiation import body_openapi, respond
from manifoundation.server.api.responses import ERRORS, READ_ERRORS
from manifoundation.server.api.submission import Admitted, SubmitterDep, read_and_submit_batch

router = APIRouter(prefix="/v1/batches", tags=["batches"], dependencies=[Authorized])
log = logging.getLogger("manifoundation.server.api.batches")


@router.post(
    "",
    status_code=202,
    dependencies=[Admitted],
    summary="Submit up to 1000 requests at once",
    openapi_extra=body_openapi("BatchCreate", "`{requests: [SynthesisRequest, ...]}` (1 to 1000 of them)."),
    responses={202: {"model": BatchPublic}, **ERRORS},
)
async def create_batch(request: Request, submitter: SubmitterDep) -> Response:
    """All or none are enqueued (owned by the caller); 202 with the batch and its first page of job ids."""
    batch_id = await read_and_submit_batch(request, submitter)
    batch = await submitter.first_page(batch_id)
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
    batch = await batch_page(queue, batch_id, caller.scope, offset, min(limit, settings.batch_page_max))
    return respond(request, batch)

