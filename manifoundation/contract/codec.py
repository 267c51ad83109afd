"""Body encodings shared by the service, the queue and the SDK: JSON and msgpack.

msgpack bodies carry arrays as typed-binary maps (see `manifoundation.contract.arrays`); unpacking is bounded (buffer
size, string, binary, array and map lengths) and never creates anything but plain types.
"""

from __future__ import annotations

import json
from typing import Any, TypeVar

import msgpack
import numpy as np
from pydantic import BaseModel

from manifoundation.contract.arrays import encode_typed

JSON = "application/json"
MSGPACK = "application/msgpack"
MSGPACK_ALIASES = frozenset({MSGPACK, "application/x-msgpack", "application/vnd.msgpack"})
MAX_BODY_BYTES = 64 * 1024 * 1024

ModelT = TypeVar("ModelT", bound=BaseModel)


class DecodeError(ValueError):
    """A body could not be decoded (malformed, oversized or of an unsupported type)."""


def media_type(content_type: str | None) -> str:
    """Normalise a Content-Type/Accept value to `JSON` or `MSGPACK` (default JSON)."""
    base = (content_type or "").split(";", 1)[0].strip().lower()
    return MSGPACK if base in MSGPACK_ALIASES else JSON


def _msgpack_default(value: Any) -> Any:
    if isinstance(value, np.ndarray):
        return encode_typed(value)
    if isinstance(value, np.generic):
        return value.item()
    raise TypeError(f"cannot encode {type(value).__name__} in msgpack")


def pack(value: Any) -> bytes:
    """msgpack-encode plain data; numpy arrays become typed-binary maps."""
    return msgpack.packb(value, default=_msgpack_default, use_bin_type=True)


def unpack(data: bytes, max_bytes: int = MAX_BODY_BYTES) -> Any:
    """Decode msgpack bytes with size limits; raises `DecodeError` on anything malformed."""
    if len(data) > max_bytes:
        raise DecodeError(f"body of {len(data)} bytes exceeds the limit of {max_bytes}")
    try:
        return msgpack.unpackb(
            data,
            raw=False,
            strict_map_key=True,
            max_str_len=min(max_bytes, 8 * 1024 * 1024),
            max_bin_len=max_bytes,
            max_array_len=1_000_000,
            max_map_len=100_000,
            max_ext_len=0,
        )
    except (msgpack.ExtraData, msgpack.FormatError, msgpack.StackError, ValueError, TypeError) as exc:
        raise DecodeError(f"malformed msgpack body: {str(exc) or exc.__class__.__name__}") from exc


def dump_model(model: BaseModel, content_type: str) -> bytes:
    """Serialise a model as JSON (arrays as lists) or msgpack (arrays as typed binary)."""
    if media_type(content_type) == MSGPACK:
        return pack(model.model_dump(mode="python", exclude_none=True))
    return model.model_dump_json(exclude_none=True).encode()


def load_model(cls: type[ModelT], data: bytes, content_type: str | None) -> ModelT:
    """Parse and validate a body of either encoding into ``cls``.

    Raises:
        DecodeError: the bytes are not valid JSON/msgpack.
        pydantic.ValidationError: the content does not satisfy the schema.
    """
    return cls.model_validate(decode_body(data, content_type))


def decode_body(data: bytes, content_type: str | None) -> Any:
    """Decode a body of either encoding into plain data (not yet validated)."""
    if media_type(content_type) == MSGPACK:
        return unpack(data)
    if len(data) > MAX_BODY_BYTES:
        raise DecodeError(f"body of {len(data)} bytes exceeds the limit of {MAX_BODY_BYTES}")
    try:
        return json.loads(data)
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise DecodeError(f"malformed JSON body: {exc}") from exc
