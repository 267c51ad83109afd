"""The service's errors and their one translation into ``{error, type, detail}`` (and a status code).

Each class is one member of the contract's `ErrorType`, which also gives its HTTP status:

    ApiError                      status + type + message (+ field errors, + headers)
    ├── BadRequest          400   malformed body (not JSON/msgpack), bad query parameter
    ├── Unauthorized        401   missing or unknown API key
    ├── NotFound            404   unknown job, batch or route
    │   └── UnknownHand     404   a hand the caller cannot use
    ├── RequestTimeout      408   the body did not arrive in time
    ├── Conflict            409   e.g. registering a built-in hand's name
    ├── PayloadTooLarge     413   body over the limit (the message gives the limit)
    ├── UnsupportedMediaType 415  a body that is neither JSON nor msgpack
    ├── InvalidInput        422   schema validation failed (detail names each field and problem)
    │   └── RobotRejected   422   a robot description the hardened loader refused
    ├── RateLimited         429   per-key token bucket empty (Retry-After)
    ├── Unavailable         503   shutting down / queue unreachable (Retry-After)
    └── DeadlineExceeded    504   a registration still loading at its deadline (its worker stopped and replaced)

Queue errors (`QueueFull`, `JobNotFound`, `RobotInvalid`, `RobotLimitReached` → 409, `RobotDeadlineExceeded` → 504,
`QueueUnavailable`), pydantic's `ValidationError` and FastAPI's own request validation are mapped here too, so routes
raise and never build error bodies.
"""

from __future__ import annotations

import logging
import math
from typing import Any

from fastapi import FastAPI, Request
from fastapi.exceptions import RequestValidationError
from pydantic import ValidationError
from starlette.exceptions import HTTPException as StarletteHTTPException
from starlette.responses import Response

from manifoundation.contract import ErrorBody, ErrorType, FieldError
from manifoundation.contract.validation import field_errors, summary
from manifoundation.server.api.encoding import respond
from manifoundation.server.queue import (
    JobNotFound,
    QueueFull,
    QueueUnavailable,
    RobotDeadlineExceeded,
    RobotInvalid,
    RobotLimitReached,
)

log = logging.getLogger("manifoundation.server.api.errors")


class ApiError(Exception):
    """An answer other than 2xx."""

    kind: ErrorType = ErrorType.INTERNAL_ERROR

    def __init__(
        self, message: str, *, detail: list[FieldError] | None = None, headers: dict[str, str] | None = None
    ) -> None:
        super().__init__(message)
        self.message = message
        self.detail = detail
        self.headers = headers or {}
        self.status = self.kind.status

    @property
    def type(self) -> str:
        """The error's name on the wire."""
        return self.kind.value

    def body(self) -> ErrorBody:
        """The wire form."""
        return ErrorBody.of(self.kind, self.message, self.detail)


class BadRequest(ApiError):
    kind = ErrorType.BAD_REQUEST


class Unauthorized(ApiError):
    kind = ErrorType.UNAUTHORIZED

    def __init__(self, message: str) -> None:
        super().__init__(message, headers={"WWW-Authenticate": "Bearer"})


class NotFound(ApiError):
    kind = ErrorType.NOT_FOUND


class UnknownHand(NotFound):
    kind = ErrorType.UNKNOWN_HAND


class RequestTimeout(ApiError):
    kind = ErrorType.REQUEST_TIMEOUT


class Conflict(ApiError):
    kind = ErrorType.CONFLICT


class PayloadTooLarge(ApiError):
    kind = ErrorType.PAYLOAD_TOO_LARGE


class UnsupportedMediaType(ApiError):
    kind = ErrorType.UNSUPPORTED_MEDIA_TYPE


class InvalidInput(ApiError):
    kind = ErrorType.VALIDATION_ERROR

    @classmethod
    def from_pydantic(cls, exc: ValidationError, root: str = "") -> InvalidInput:
        """One `FieldError` per problem, message = the first problem."""
        errors = field_errors(exc, root=root)
        return cls(summary(errors), detail=errors)


class RobotRejected(InvalidInput):
    kind = ErrorType.ROBOT_INVALID


class RateLimited(ApiError):
    kind = ErrorType.RATE_LIMITED

    def __init__(self, message: str, retry_after: float) -> None:
        super().__init__(message, headers={"Retry-After": retry_after_header(retry_after)})


class QueueFullError(ApiError):
    kind = ErrorType.QUEUE_FULL

    def __init__(self, message: str, retry_after: float) -> None:
        super().__init__(message, headers={"Retry-After": retry_after_header(retry_after)})


class Unavailable(ApiError):
    kind = ErrorType.UNAVAILABLE

    def __init__(self, message: str, retry_after: float = 5.0) -> None:
        super().__init__(message, headers={"Retry-After": retry_after_header(retry_after)})


class DeadlineExceeded(ApiError):
    kind = ErrorType.DEADLINE_EXCEEDED


def retry_after_header(seconds: float) -> str:
    """Retry-After takes whole seconds; round up, at least 1."""
    return str(max(1, math.ceil(seconds))) if math.isfinite(seconds) else "60"


def from_exception(exc: Exception) -> ApiError:
    """Translate any exception a route can raise into an `ApiError`."""
    if isinstance(exc, ApiError):
        return exc
    if isinstance(exc, ValidationError):
        return InvalidInput.from_pydantic(exc)
    if isinstance(exc, RequestValidationError):
        errors = [
            FieldError(field=".".join(str(p) for p in e["loc"]) or "request", problem=str(e["msg"]))
            for e in exc.errors()
        ]
        return InvalidInput(summary(errors), detail=errors)
    if isinstance(exc, QueueFull):
        return QueueFullError(str(exc) or "queue is full", exc.retry_after)
    if isinstance(exc, JobNotFound):
        return NotFound(str(exc) or "not found")
    if isinstance(exc, RobotInvalid):
        message = str(exc) or "robot description rejected"
        field, sep, problem = message.partition(": ")
        if sep and field.replace("_", "").replace(".", "").isalnum():  # the worker named the field already
            return RobotRejected(message, detail=[FieldError(field=field, problem=problem)])
        return RobotRejected(f"urdf: {message}", detail=[FieldError(field="urdf", problem=message)])
    if isinstance(exc, RobotLimitReached):
        return Conflict(str(exc))
    if isinstance(exc, RobotDeadlineExceeded):
        return DeadlineExceeded(str(exc))
    if isinstance(exc, QueueUnavailable):
        return Unavailable(str(exc) or "queue unavailable")
    if isinstance(exc, StarletteHTTPException):
        kind = _BY_HTTP_STATUS.get(exc.status_code, ErrorType.BAD_REQUEST)
        err = ApiError(str(exc.detail), headers=dict(exc.headers or {}))
        err.kind, err.status = kind, exc.status_code
        return err
    return ApiError("internal error")


_BY_HTTP_STATUS: dict[int, ErrorType] = {
    400: ErrorType.BAD_REQUEST,
    401: ErrorType.UNAUTHORIZED,
    404: ErrorType.NOT_FOUND,
    405: ErrorType.METHOD_NOT_ALLOWED,
    413: ErrorType.PAYLOAD_TOO_LARGE,
    415: ErrorType.UNSUPPORTED_MEDIA_TYPE,
}
"""Starlette's own errors (routing, body limits) by status; any other 4xx it raises reads as BadRequest."""


def route_table(app: Any) -> list[tuple[str, Any, set[str]]]:
    """``(path template, path regex, methods)`` of every route, included routers' too (FastAPI ≥ 0.165 keeps an
    included router as one entry of ``app.routes`` and exposes its routes as "effective candidates")."""
    table = []
    for route in app.routes:
        contexts = route.effective_candidates() if hasattr(route, "effective_candidates") else [route]
        for ctx in contexts:
            regex, methods = getattr(ctx, "path_regex", None), getattr(ctx, "methods", None)
            if regex is not None:
                table.append((str(getattr(ctx, "path", "")), regex, set(methods or ())))
    return table


def allowed_methods(request: Request) -> list[str]:
    """Every method some route serves at this path (Starlette's 405 names only the first matching route's)."""
    methods: set[str] = set()
    for _, regex, served in route_table(request.app):
        if regex.match(request.url.path):
            methods |= served
    return sorted(methods)


async def handle(request: Request, exc: Exception) -> Response:
    """The one exception handler: every error becomes ``ErrorBody`` in the negotiated encoding."""
    error = from_exception(exc)
    if error.status == 405:
        error.headers["Allow"] = ", ".join(allowed_methods(request))
    if error.status >= 500 and not isinstance(error, Unavailable | DeadlineExceeded):
        log.error("unhandled error", exc_info=exc)
    request.state.error_type = error.type
    return respond(request, error.body(), status=error.status, headers=error.headers)


def install(app: FastAPI) -> None:
    """Register the handler for every exception class a route may raise."""
    for cls in (
        ApiError,
        ValidationError,
        RequestValidationError,
        StarletteHTTPException,
        QueueFull,
        JobNotFound,
        RobotInvalid,
        RobotLimitReached,
        RobotDeadlineExceeded,
        QueueUnavailable,
        Exception,
    ):
        app.add_exception_handler(cls, handle)
