"""JSON and msgpack both ways: read a body by its Content-Type, answer in the encoding the Accept header asks for.

Bodies are read here (not by FastAPI) so that msgpack works and the size limit holds while streaming: a body
over the limit is refused as soon as its Content-Length (or its running size) says so.
"""

from __future__ import annotations

from typing import Any, TypeVar

from pydantic import BaseModel, ValidationError
from starlette.requests import Request
from starlette.responses import Response

from clients.codec import JSON, MSGPACK, DecodeError, dump_model, load_model, media_type

ModelT = TypeVar("ModelT", bound=BaseModel)
BODY_MEDIA_TYPES = (JSON, MSGPACK)


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


async def read_bytes(request: Request, limit: int) -> bytes:
    """The raw body, refusing more than ``limit`` bytes (413)."""
    from service.errors import BadRequest, PayloadTooLarge

    declared = request.headers.get("content-length")
    if declared is not None:
        try:
            size = int(declared)
        except ValueError as exc:
            raise BadRequest("Content-Length is not a number") from exc
        if size > limit:
            raise PayloadTooLarge(f"body of {size} bytes exceeds the limit of {limit} bytes")
    chunks: list[bytes] = []
    total = 0
    async for chunk in request.stream():
        total += len(chunk)
        if total > limit:
            raise PayloadTooLarge(f"body exceeds the limit of {limit} bytes")
        chunks.append(chunk)
    return b"".join(chunks)


async def read_model(request: Request, cls: type[ModelT], limit: int) -> ModelT:
    """Read, decode and validate a body of ``cls`` (400 malformed, 413 too big, 415 other type, 422 invalid)."""
    from service.errors import BadRequest, InvalidInput, UnsupportedMediaType

    content_type = request.headers.get("content-type")
    base = (content_type or JSON).split(";", 1)[0].strip().lower()
    if base not in (JSON, "text/json") and media_type(base) != MSGPACK and not base.endswith("+json"):
        raise UnsupportedMediaType(f"Content-Type {base!r} is not supported; use {JSON} or {MSGPACK}")
    data = await read_bytes(request, limit)
    if not data:
        raise BadRequest("empty body; send a JSON or msgpack object")
    try:
        return load_model(cls, data, content_type)
    except DecodeError as exc:
        raise BadRequest(str(exc)) from exc
    except ValidationError as exc:
        raise InvalidInput.from_pydantic(exc) from exc
    except (ValueError, TypeError, RecursionError) as exc:
        raise BadRequest(f"body could not be read: {exc}") from exc


def body_openapi(schema_ref: str, description: str = "") -> dict[str, Any]:
    """``openapi_extra`` documenting a body of ``#/components/schemas/<schema_ref>`` in both encodings."""
    ref = {"$ref": f"#/components/schemas/{schema_ref}"}
    return {
        "requestBody": {
            "required": True,
            "description": description or f"{schema_ref} as JSON, or msgpack with typed-binary arrays.",
            "content": {JSON: {"schema": ref}, MSGPACK: {"schema": ref}},
        }
    }
