"""`/healthz` (live), `/readyz` (queue answers and a live worker has its model), `/metrics` (Prometheus)."""

from __future__ import annotations

from fastapi import APIRouter, Request
from prometheus_client import CONTENT_TYPE_LATEST
from starlette.responses import Response

from manifoundation.contract import HealthPublic, ReadyPublic
from manifoundation.server.api.deps import Authorized, MetricsDep, QueueDep
from manifoundation.server.api.negotiation import respond
from manifoundation.server.api.responses import errors
from manifoundation.server.api.services import services_of

router = APIRouter(tags=["health"], dependencies=[Authorized])


@router.get("/healthz", summary="Liveness", responses={200: {"model": HealthPublic}})
async def healthz(request: Request) -> Response:
    services = services_of(request)
    queue, versions = services.queue, services.versions
    backend = getattr(queue, "backend", "none")
    body = HealthPublic(backend=backend, version=versions.service, contract_version=versions.contract)
    return respond(request, body)


@router.get(
    "/readyz",
    summary="Readiness: queue answers, a live worker has its model loaded",
    responses={200: {"model": ReadyPublic}, 503: {"model": ReadyPublic, "description": "Not ready"}},
)
async def readyz(request: Request, queue: QueueDep) -> Response:
    try:
        up = await queue.ping()
        workers = await queue.workers() if up else []
    except Exception as exc:
        body = ReadyPublic(ready=False, queue=False, workers=0, model_loaded=False, detail=f"queue: {exc}")
        return respond(request, body, status=503)
    loaded = any(w.model_loaded for w in workers)
    ready = up and loaded
    detail = (
        None
        if ready
        else (
            "queue does not answer"
            if not up
            else "no live worker"
            if not workers
            else "no live worker has its model loaded"
        )
    )
    body = ReadyPublic(ready=ready, queue=up, workers=len(workers), model_loaded=loaded, detail=detail)
    return respond(request, body, status=200 if ready else 503, headers=None if ready else {"Retry-After": "5"})


@router.get(
    "/metrics",
    summary="Prometheus metrics",
    response_class=Response,
    responses={200: {"content": {CONTENT_TYPE_LATEST: {}}}, **errors(401)},
)
async def metrics(queue: QueueDep, collectors: MetricsDep) -> Response:
    await collectors.refresh(queue)
    return Response(collectors.render(), media_type=CONTENT_TYPE_LATEST)
