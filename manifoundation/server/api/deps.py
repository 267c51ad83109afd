"""Dependencies of the routes: ``Annotated`` aliases over the app's `AppServices`."""

from __future__ import annotations

from typing import Annotated

from fastapi import Depends, Request

from manifoundation.server.api.dashboard import History
from manifoundation.server.api.errors import RateLimited, Unauthorized, Unavailable
from manifoundation.server.api.metrics import Metrics
from manifoundation.server.api.robots import RobotCatalog
from manifoundation.server.api.security import Caller, check_key, tenant_of
from manifoundation.server.api.services import services_of
from manifoundation.server.api.settings import Settings
from manifoundation.server.queue import JobQueue


async def get_settings(request: Request) -> Settings:
    return services_of(request).settings


async def get_queue(request: Request) -> JobQueue:
    queue = services_of(request).queue
    if queue is None:
        raise Unavailable("the queue is not running")
    return queue


async def get_metrics(request: Request) -> Metrics:
    return services_of(request).metrics


async def get_robots(request: Request) -> RobotCatalog:
    return services_of(request).catalog()


async def get_history(request: Request) -> History:
    history = services_of(request).history
    if history is None:
        raise Unavailable("the service is not started")
    return history


async def get_request_id(request: Request) -> str:
    return str(request.state.request_id)


SettingsDep = Annotated[Settings, Depends(get_settings)]
QueueDep = Annotated[JobQueue, Depends(get_queue)]
MetricsDep = Annotated[Metrics, Depends(get_metrics)]
RobotsDep = Annotated[RobotCatalog, Depends(get_robots)]
HistoryDep = Annotated[History, Depends(get_history)]
RequestIdDep = Annotated[str, Depends(get_request_id)]


async def authorize(request: Request, settings: SettingsDep) -> Caller:
    """Bearer key when keys are configured (except on ``open_paths``), then the caller's token bucket; answers
    who is calling (FastAPI runs it once per request however many routes' parameters ask for it)."""
    identity = request.client.host if request.client else "unknown"
    caller = Caller()
    if settings.auth_enabled and request.url.path not in settings.open_paths:
        failures = services_of(request).auth_failures
        if wait := failures.blocked(identity):  # too many wrong keys from this address: no more guesses
            raise RateLimited("too many requests with a wrong API key from this address", wait)
        try:
            key = check_key(request.headers.get("authorization"), settings.all_keys)
        except Unauthorized:
            failures.take(identity)
            raise
        identity = "key:" + key
        caller = Caller(tenant=tenant_of(key), admin=key in settings.admin_keys)
    limiter = services_of(request).limiter
    limiter.take(identity)
    return caller


Authorized = Depends(authorize)
CallerDep = Annotated[Caller, Depends(authorize)]
