"""What the front ends share, typed: the settings, the queue and everything the lifespan starts, in one object.

HTTP routes reach it through `services_of(request)` (or the dependencies in `manifoundation.server.api.deps`); gRPC
and MCP are handed it when they start. It replaces an untyped ``app.state`` bag; ``app.state.services`` holds it so
that Starlette code that only has the app can still find it.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Protocol

from starlette.requests import Request
from starlette.types import ASGIApp

from manifoundation.server.api.bodies import BodyPool
from manifoundation.server.api.errors import Unavailable
from manifoundation.server.api.mcp.objects import ObjectStore
from manifoundation.server.api.metrics import Metrics
from manifoundation.server.api.scenes import SceneStore
from manifoundation.server.api.security import RateLimiter
from manifoundation.server.api.settings import Settings
from manifoundation.server.api.versions import Versions
from manifoundation.server.queue import JobQueue

if TYPE_CHECKING:
    from fastapi import FastAPI

    from manifoundation.server.api.dashboard import History
    from manifoundation.server.api.robots import RobotCatalog


class Stoppable(Protocol):
    """A server the lifespan stops (the gRPC server)."""

    async def stop(self) -> None: ...


class McpApp(Protocol):
    """The MCP SDK's app, started on first use (`manifoundation.server.api.mcp.host.McpHost`)."""

    async def app(self) -> ASGIApp: ...

    async def close(self) -> None: ...


@dataclass(eq=False)
class AppServices:
    """One app's shared objects. Those the lifespan starts are None before it (and the queue while it is down)."""

    settings: Settings
    metrics: Metrics
    limiter: RateLimiter
    auth_failures: RateLimiter
    scenes: SceneStore
    objects: ObjectStore
    bodies: BodyPool
    versions: Versions = field(default_factory=Versions)
    """Reported on every answer (`manifoundation.server.api.versions`); a test may make an app report another."""
    queue: JobQueue | None = None
    robots: RobotCatalog | None = None
    history: History | None = None
    mcp: McpApp | None = None
    grpc: Stoppable | None = None
    shutting_down: bool = False

    def catalog(self) -> RobotCatalog:
        """The hands' catalog while the service runs; `Unavailable` before the lifespan started it."""
        if self.robots is None:
            raise Unavailable("the service is not started")
        return self.robots

    @classmethod
    def build(cls, settings: Settings, metrics: Metrics) -> AppServices:
        """The objects that exist before the lifespan (limits, stores, the body pool)."""
        return cls(
            settings=settings,
            metrics=metrics,
            limiter=RateLimiter(settings.rate_limit_per_s, settings.rate_limit_burst),
            auth_failures=RateLimiter(settings.auth_failures_per_s, settings.auth_failures_burst),
            scenes=SceneStore(),
            objects=ObjectStore(settings.object_ttl_s, settings.max_objects, settings.max_object_store_bytes),
            bodies=BodyPool(settings.parse_offload_bytes, settings.large_body_slots, settings.body_timeout),
        )


def services_of(where: Request | FastAPI) -> AppServices:
    """The services of a request's app (or of an app)."""
    app = where.app if isinstance(where, Request) else where
    services: AppServices = app.state.services
    return services
