"""The FastAPI application: `create_app(settings)`; what its front ends share is one `AppServices`."""

from __future__ import annotations

import asyncio
import contextlib
import logging
from collections.abc import AsyncIterator
from typing import Any

from fastapi import FastAPI
from fastapi.openapi.utils import get_openapi
from pydantic.json_schema import models_json_schema
from starlette.routing import Route

from manifoundation.contract import BatchCreate, ErrorBody, PlanRequest, RobotRegister, SynthesisRequest
from manifoundation.server.api import errors, logs
from manifoundation.server.api.dashboard import History
from manifoundation.server.api.mcp.endpoint import PATH as MCP_PATH
from manifoundation.server.api.mcp.endpoint import McpEndpoint
from manifoundation.server.api.mcp.host import McpHost
from manifoundation.server.api.metrics import Metrics
from manifoundation.server.api.middleware import RequestContext
from manifoundation.server.api.robots import RobotCatalog
from manifoundation.server.api.routes import batches, health, jobs, pages, plans, robots, synthesis
from manifoundation.server.api.services import AppServices
from manifoundation.server.api.settings import Settings
from manifoundation.server.api.versions import SERVICE_VERSION
from manifoundation.server.queue import JobQueue

log = logging.getLogger("manifoundation.server.api.app")
API_DESCRIPTION = """Contact synthesis for robot manipulation (ManiFoundation).

Every body may be JSON or msgpack (`Content-Type` / `Accept`: `application/json`, `application/msgpack`); in
msgpack, arrays travel as typed binary (`{dtype, shape, data}`). Every error is `{error, type, detail}`.
With API keys configured, `/v1` needs `Authorization: Bearer <key>`."""


def build_queue(settings: Settings) -> JobQueue:
    """The queue the settings ask for: Redis Streams with ``redis_url``, else embedded workers."""
    from manifoundation.server.queue import create_queue

    return create_queue(settings.queue_settings())


def create_app(settings: Settings | None = None, *, queue: JobQueue | None = None, grpc: bool = False) -> FastAPI:
    """The app. ``queue``: an already-built queue (tests); the lifespan starts and closes it either way.
    ``grpc``: also serve gRPC on ``settings.grpc_port`` (unless 0) from the lifespan, over the same queue
    (`mani serve` asks for it; `AppServices.grpc` is the running `manifoundation.server.api.grpc.server.GrpcServer`)."""
    settings = settings or Settings()
    metrics = Metrics()
    services = AppServices.build(settings, metrics)

    @contextlib.asynccontextmanager
    async def lifespan(app: FastAPI) -> AsyncIterator[None]:
        the_queue = queue or build_queue(settings)
        await the_queue.start()
        history = History(the_queue, settings.dashboard_sample_s, settings.dashboard_history)
        services.queue = the_queue
        services.robots = RobotCatalog(the_queue, settings.robots_cache_s)
        services.history = history
        services.shutting_down = False  # an app started again after a shutdown serves again
        services.mcp = McpHost(services)  # started by the first /mcp request
        sampler = asyncio.create_task(history.run(), name="dashboard-sampler")
        services.grpc = None
        if grpc and settings.grpc_port:
            from manifoundation.server.api.grpc.server import start_grpc

            services.grpc = await start_grpc(services, settings)
        log.info("service started", extra={"backend": the_queue.backend})
        try:
            yield
        finally:
            services.shutting_down = True
            await services.mcp.close()
            if services.grpc is not None:
                await services.grpc.stop()
            sampler.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await sampler
            await the_queue.close()
            services.bodies.close()
            services.objects.close()
            log.info("service stopped")

    app = FastAPI(
        title="ManiFoundation Service",
        version=SERVICE_VERSION,
        description=API_DESCRIPTION,
        lifespan=lifespan,
        docs_url=None,  # served by `pages.docs` from the installed Swagger UI bundle: no CDN
    )
    app.state.services = services
    errors.install(app)
    for router in (
        health.router,
        synthesis.router,
        plans.router,
        jobs.router,
        batches.router,
        robots.router,
        pages.data,
        pages.pages,
    ):
        app.include_router(router)
    if settings.mcp:
        app.router.routes.append(Route(MCP_PATH, McpEndpoint(services), methods=["GET", "POST", "DELETE"]))
    app.add_middleware(RequestContext, metrics=metrics, services=services)
    app.openapi = lambda: _openapi(app)  # type: ignore[method-assign]
    return app


def _openapi(app: FastAPI) -> dict[str, Any]:
    """FastAPI's schema plus the body schemas that routes read themselves (JSON or msgpack)."""
    if app.openapi_schema:
        return app.openapi_schema
    schema = get_openapi(title=app.title, version=app.version, description=app.description, routes=app.routes)
    _, defs = models_json_schema(
        [(m, "validation") for m in (SynthesisRequest, BatchCreate, RobotRegister, PlanRequest)],
        ref_template="#/components/schemas/{model}",
    )
    components = schema.setdefault("components", {}).setdefault("schemas", {})
    for name, definition in defs.get("$defs", {}).items():
        components.setdefault(name, definition)
    # FastAPI documents query-parameter errors with its own 422 shape; ours is ErrorBody everywhere.
    components.setdefault("ErrorBody", ErrorBody.model_json_schema(ref_template="#/components/schemas/{model}"))
    error_ref = {"$ref": "#/components/schemas/ErrorBody"}
    for operations in schema.get("paths", {}).values():
        for operation in operations.values():
            invalid = operation.get("responses", {}).get("422")
            if invalid and "HTTPValidationError" in str(invalid):
                invalid["description"] = "Validation failed: `detail` names each field and problem"
                invalid["content"] = {"application/json": {"schema": error_ref}}
    for name in ("HTTPValidationError", "ValidationError"):
        components.pop(name, None)
    app.openapi_schema = schema
    return schema


def configure_logging(settings: Settings) -> None:
    """JSON (or text) logs at the configured level (the CLI calls this once per process)."""
    logs.configure(settings.log_level, settings.log_format == "json")
