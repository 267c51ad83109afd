"""One ASGI middleware around every request: request id, the reported versions, 503 while shutting down, metrics and
an access log."""

from __future__ import annotations

import logging
import re
import time
import uuid
from typing import TYPE_CHECKING

from starlette.types import ASGIApp, Message, Receive, Scope, Send

from manifoundation.server.api.errors import Unavailable
from manifoundation.server.api.logs import request_id_var
from manifoundation.server.api.metrics import Metrics
from manifoundation.server.api.negotiation import respond

if TYPE_CHECKING:
    from manifoundation.server.api.services import AppServices

REQUEST_ID_HEADER = "x-request-id"
_VALID_ID = re.compile(r"^[A-Za-z0-9._:\-]{1,128}$")

log = logging.getLogger("manifoundation.server.api.access")


def request_id_from(headers: list[tuple[bytes, bytes]]) -> str:
    """The caller's ``X-Request-ID`` when it is sane (≤ 128 of ``[A-Za-z0-9._:-]``), else a fresh one."""
    for name, value in headers:
        if name.lower() == REQUEST_ID_HEADER.encode():
            text = value.decode("latin-1").strip()
            if _VALID_ID.match(text):
                return text
    return uuid.uuid4().hex


class RequestContext:
    """Request id in/out, refuse `/v1` work while shutting down, time and count every request."""

    def __init__(self, app: ASGIApp, metrics: Metrics, services: AppServices) -> None:
        self.app = app
        self.metrics = metrics
        self.services = services

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        request_id = request_id_from(scope.get("headers", []))
        scope.setdefault("state", {})["request_id"] = request_id
        token = request_id_var.set(request_id)
        start = time.perf_counter()
        status = 500
        observed = False

        def observe() -> None:
            nonlocal observed
            if observed:
                return
            observed = True
            route = scope.get("route")
            template = getattr(route, "path", None) or "unmatched"
            elapsed = time.perf_counter() - start
            self.metrics.requests.labels(scope["method"], template, str(status)).inc()
            self.metrics.request_duration.labels(scope["method"], template).observe(elapsed)
            log.info(
                "request",
                extra={
                    "method": scope["method"],
                    "path": scope["path"],
                    "route": template,
                    "status": status,
                    "duration_ms": round(elapsed * 1000, 3),
                    "job_id": scope["state"].get("job_id"),
                },
            )

        async def send_wrapper(message: Message) -> None:
            nonlocal status
            if message["type"] == "http.response.start":
                status = message["status"]
                headers = list(message.get("headers", []))
                headers.append((b"x-request-id", request_id.encode()))
                headers.extend(self.services.versions.raw_headers())
                message = {**message, "headers": headers}
                observe()
            await send(message)

        self.metrics.in_flight.inc()
        try:
            if self.services.shutting_down and scope["path"].startswith("/v1"):
                from starlette.requests import Request

                err = Unavailable("the service is shutting down", retry_after=5)
                response = respond(Request(scope), err.body(), status=err.status, headers=err.headers)
                await response(scope, receive, send_wrapper)
                return
            await self.app(scope, receive, send_wrapper)
        finally:
            observe()
            self.metrics.in_flight.dec()
            request_id_var.reset(token)
