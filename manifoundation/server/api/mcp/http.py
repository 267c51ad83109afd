"""The MCP tool server as the service mounts it (streamable HTTP at ``/mcp``; `manifoundation.server.api.mcp.endpoint`
starts it).

Each request reaching it was authenticated as a ``/v1`` request (`McpEndpoint`: the same API keys, wrong-key
throttle and token bucket); its tools act for that `Caller` through the routes' `Submitter` and tenant-scoped reads
(`manifoundation.server.api.mcp.backend.ServiceBackend`), and uploaded objects are kept per tenant
(``AppServices.objects``). The SDK runs stateless with JSON answers: every POST stands alone (no server-side session
to hijack or to pin to a replica). Its Host-header check is off, as for the rest of the API: exposure is decided by
the API keys (set them for anything beyond a trusted host).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from mcp.server.mcpserver import Context, MCPServer
from mcp.server.transport_security import TransportSecuritySettings
from starlette.requests import Request
from starlette.types import ASGIApp

from manifoundation.server.api.errors import Unavailable
from manifoundation.server.api.mcp.backend import ServiceBackend
from manifoundation.server.api.mcp.endpoint import CALLER_KEY, PATH
from manifoundation.server.api.mcp.tools import Session, SessionFn, build_server
from manifoundation.server.api.mcp.uploads import STAGED_KEY, Staged
from manifoundation.server.api.security import Caller

if TYPE_CHECKING:
    from manifoundation.server.api.services import AppServices


def session_maker(services: AppServices) -> SessionFn:
    """Each call's `Session`: the caller `McpEndpoint` authorized, over the app's shared objects."""

    async def session_of(ctx: Context) -> Session:
        request = ctx.request_context.request
        if not isinstance(request, Request):
            raise Unavailable("no HTTP request behind this MCP call")
        scope_state = request.scope.get("state", {})
        caller: Caller = scope_state.get(CALLER_KEY) or Caller()
        backend = ServiceBackend(services, caller, str(scope_state.get("request_id", "")), str(request.base_url))
        staged: Staged | None = scope_state.get(STAGED_KEY)
        return Session(backend, tenant=caller.tenant or "", files=False, staged=staged)

    return session_of


def build_app(services: AppServices) -> tuple[MCPServer, ASGIApp]:
    """A fresh SDK server and its ASGI app (the caller runs ``server.session_manager.run()`` around its use)."""
    server = build_server(services.objects, session_maker(services))
    app = server.streamable_http_app(
        streamable_http_path=PATH, stateless_http=True, json_response=True,
        max_request_body_size=services.settings.mcp_max_body_bytes,
        transport_security=TransportSecuritySettings(enable_dns_rebinding_protection=False),
    )  # fmt: skip
    return server, app
