"""Large ``upload_object`` calls, decoded off the event loop.

The MCP SDK reads and parses every ``POST /mcp`` body on the event loop (JSON, then the JSON-RPC model, then the
tool's arguments): a few-MB cloud holds the loop for hundreds of milliseconds. A body over
``MANI_PARSE_OFFLOAD_BYTES`` is therefore streamed to one of the service's body processes
(`manifoundation.server.api.bodies.BodyPool`), where `stage_upload` parses it and validates the cloud as the
contract's `ObjectIn`; the SDK then gets the same call with its arrays emptied (a few hundred bytes) and the tool
takes the object decoded there (`Staged`, left in the request's ASGI scope by the ``/mcp`` endpoint). Only
``upload_object`` carries arrays: any other call goes to the SDK as sent up to `CALL_MAX_BYTES`, and is refused
(413) beyond.

`object_from_arrays` is the one rule from a tool's array arguments to an `ObjectIn`, for small calls (in the tool)
and large ones (here). Imports the contract and pydantic only (it runs in the body processes).
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from typing import Any

from pydantic import ValidationError

from manifoundation.contract import FieldError, ObjectIn
from manifoundation.contract.validation import field_errors

TOOL = "upload_object"
ARRAYS = ("points", "normals", "mesh_vertices", "mesh_faces")
"""The arguments of `TOOL` that carry arrays (emptied in the call the SDK sees)."""
STAGED_KEY = "mani_staged_upload"
"""Where the ``/mcp`` endpoint leaves a `Staged` in the ASGI scope's state for the tool."""
CALL_MAX_BYTES = 1 << 20
"""The largest MCP call other than ``upload_object`` (its other tools take ids and a few numbers: a 1 MiB body
parses in milliseconds on the event loop), whatever ``MANI_PARSE_OFFLOAD_BYTES`` says."""
DECODER = "manifoundation.server.api.mcp.uploads:stage_upload"
"""`stage_upload`, as a body process is told to run it."""


@dataclass(frozen=True)
class Staged:
    """An ``upload_object`` call decoded in a body process: ``call``, the JSON-RPC message with its arrays emptied
    (for the SDK), and what its arrays are: the object, or the problems that make it invalid (None: it carried
    no ``points``; the tool then reads its other arguments as usual)."""

    call: bytes
    object: ObjectIn | None = None
    errors: list[FieldError] | None = None


def object_from_arrays(
    points: Any, normals: Any, vertices: Any, faces: Any, friction: float | None = None
) -> ObjectIn:  # fmt: skip
    """The object a tool's array arguments describe, validated by the contract (raises pydantic's
    ValidationError)."""
    mesh = None if vertices is None and faces is None else {"vertices": vertices, "faces": faces}
    properties = {} if friction is None else {"friction": friction}
    return ObjectIn.model_validate({"points": points, "normals": normals, "mesh": mesh, "properties": properties})


def stage_upload(data: bytes, small: int) -> tuple[str, Any]:
    """Decode a ``POST /mcp`` body of undeclared or large size (in a body process): ``("staged", Staged)`` for an
    ``upload_object`` call; ``("as_is", data)`` for any other body of at most ``small`` bytes (the SDK reads it as
    it reads every small body); ``("other", what)`` for a larger one, ``("decode", message)`` for a larger one
    that is not JSON."""
    try:
        message = json.loads(data)
    except (ValueError, RecursionError) as exc:
        return ("as_is", data) if len(data) <= small else ("decode", f"body is not JSON: {exc}")
    params = message.get("params") if isinstance(message, dict) else None
    if not isinstance(params, dict) or message.get("method") != "tools/call" or params.get("name") != TOOL:
        if len(data) <= small:
            return "as_is", data
        method = message.get("method") if isinstance(message, dict) else None
        tool = params.get("name") if isinstance(params, dict) else None
        return "other", f"{method} {tool}" if tool else f"{method or 'a JSON-RPC batch or response'}"
    arguments = params.get("arguments")
    if not isinstance(arguments, dict):
        return "staged", Staged(json.dumps(message).encode())
    arrays = {name: arguments[name] for name in ARRAYS if name in arguments}
    arguments.update({name: [] for name in arrays})
    call = json.dumps(message).encode()
    if arrays.get("points") is None:
        return "staged", Staged(call)
    friction = arguments.get("friction")
    friction = friction if isinstance(friction, int | float) else None  # a bad one: the SDK's error, as for small
    try:
        points, normals, vertices, faces = (arrays.get(name) for name in ARRAYS)
        obj = object_from_arrays(points, normals, vertices, faces, friction)
    except ValidationError as exc:
        return "staged", Staged(call, errors=field_errors(exc))
    return "staged", Staged(call, object=obj)
