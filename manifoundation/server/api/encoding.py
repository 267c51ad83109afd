"""Answers in the encoding the caller's Accept header asks for: JSON (default) or msgpack.

Imports nothing else of the service, so that the error handler (`manifoundation.server.api.errors`) and the body reader
(`manifoundation.server.api.negotiation`) can both use it without importing each other in a circle.
"""

from __future__ import annotations

from pydantic import BaseModel
from starlette.requests import Request
from starlette.responses import Response

from manifoundation.contract.codec import JSON, MSGPACK, dump_model, media_type


def accepted(request: Request) -> str:
    """`MSGPACK` when the Accept header prefers it (by q-value, then order), else `JSON`."""
    best, best_q = JSON, -1.0
    for part in request.headers.get("accept", "").split(","):
        kind, _, params = part.partition(";")
        kind = kind.strip().lower()
        if not kind:
            continue
        q = 1.0
        for param in params.split(";"):
            name, _, value = param.partition("=")
            if name.strip() == "q":
                try:
                    q = float(value)
                except ValueError:
                    q = 0.0
        choice = MSGPACK if media_type(kind) == MSGPACK else JSON if kind in _JSON_LIKE else None
        if choice is not None and q > best_q:
            best, best_q = choice, q
    return best


_JSON_LIKE = frozenset({JSON, "application/*", "*/*"})


def respond(
    request: Request, model: BaseModel, *, status: int = 200, headers: dict[str, str] | None = None
) -> Response:
    """Serialise ``model`` in the negotiated encoding."""
    kind = accepted(request)
    return Response(dump_model(model, kind), status_code=status, media_type=kind, headers=headers)
