"""The MCP SDK's ASGI app as the service runs it: started on first use (importing the SDK costs about a second:
`mani serve` does not pay it until an agent calls), stopped with the service.

The SDK's app and its session manager live in one task (`McpHost._serve`: an anyio task group must be left by the
task that entered it) from the first ``/mcp`` request to the app's shutdown (`McpHost.close`, from the lifespan).
"""

from __future__ import annotations

import asyncio
import contextlib
import importlib
from typing import TYPE_CHECKING

from starlette.types import ASGIApp

from manifoundation.server.api.errors import Unavailable

if TYPE_CHECKING:
    from manifoundation.server.api.services import AppServices


class McpHost:
    """The MCP SDK's ASGI app, started on first use and stopped with the service."""

    def __init__(self, services: AppServices) -> None:
        self.services = services
        self._task: asyncio.Task[None] | None = None
        self._ready = asyncio.Event()
        self._stop = asyncio.Event()
        self._app: ASGIApp | None = None
        self._failure: BaseException | None = None

    async def app(self) -> ASGIApp:
        """The running app (started now if it is not yet)."""
        if self.services.shutting_down or self._stop.is_set():
            raise Unavailable("the service is shutting down")
        if self._task is None:
            self._task = asyncio.create_task(self._serve(), name="mcp-streamable-http")
        await self._ready.wait()
        if self._app is None:
            raise Unavailable(f"the MCP server did not start: {self._failure}")
        return self._app

    async def _serve(self) -> None:
        try:
            http = await asyncio.to_thread(
                importlib.import_module, "manifoundation.server.api.mcp.http"
            )  # off the event loop
            server, app = http.build_app(self.services)
            async with server.session_manager.run():
                self._app = app
                self._ready.set()
                await self._stop.wait()
        except Exception as exc:  # answered as 503 to every caller, never a crash of the service
            self._failure = exc
        finally:
            self._app = None
            self._ready.set()

    async def close(self) -> None:
        """Stop the app (the lifespan calls this at shutdown)."""
        self._stop.set()
        if self._task is not None:
            with contextlib.suppress(asyncio.CancelledError):
                await self._task
