"""`POST /v1/plans`: plan a manipulation (an async job, 202 at once); follow it at `/v1/jobs/{id}`."""

from __future__ import annotations

from fastapi import APIRouter, Request
from starlette.responses import Response

from manifoundation.contract import JobCreated, PlanRequest
from manifoundation.server.api.deps import Authorized
from manifoundation.server.api.negotiation import body_openapi
from manifoundation.server.api.responses import ERRORS
from manifoundation.server.api.routes.synthesis import job_created
from manifoundation.server.api.submission import Admitted, SubmitterDep, read_and_submit

router = APIRouter(prefix="/v1", tags=["plans"], dependencies=[Authorized])


@router.post(
    "/plans",
    status_code=202,
    dependencies=[Admitted],
    summary="Plan a manipulation: waypoints → a collision-free trajectory with contacts at every step",
    openapi_extra=body_openapi(
        "PlanRequest",
        "`PlanRequest` (object, start pose, waypoints, scene, robot, options) as JSON, or msgpack with typed-binary"
        " arrays.",
    ),
    responses={202: {"model": JobCreated}, **ERRORS},
)
async def create_plan(request: Request, submitter: SubmitterDep) -> Response:
    """202 with the job's URL at once. The job's progress goes by stage (``repair``, ``planning`` per segment,
    ``contacts`` per step: ``progress.completed`` of ``progress.total``); `GET /v1/jobs/{id}` answers the
    `PlanResult` in ``plan``. A waypoint in collision that is not repaired ends the job ``InfeasibleWaypoint``, a
    segment without a path ``NoPathFound`` (both 422, ``detail`` naming the waypoint). ``options.timeout`` bounds
    the plan's compute; the job itself has no queue deadline (an asynchronous caller comes back for it)."""
    _, job_id = await read_and_submit(request, submitter, "plan", deadline_from_timeout=False, model=PlanRequest)
    return job_created(request, job_id)
