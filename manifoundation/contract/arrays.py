"""Arrays on the wire: nested lists in JSON, typed binary in msgpack, numpy in Python.

A typed binary array is the map ``{"dtype": "float32", "shape": [N, 3], "data": <bytes>}`` (little endian,
C order). Only the dtypes in `WIRE_DTYPES` are accepted, ``prod(shape) * itemsize`` must equal ``len(data)``,
and nothing is ever unpickled or given an object dtype. The same rules apply to queue payloads, which are
input too.

``Annotated[np.ndarray, spec(...)]`` is a pydantic field type that accepts any of the three forms, checks
shape, dtype and finiteness, and serialises back to lists (JSON mode) or leaves the numpy array for the msgpack encoder.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from pydantic import GetCoreSchemaHandler, GetJsonSchemaHandler
from pydantic.json_schema import JsonSchemaValue
from pydantic_core import core_schema

WIRE_DTYPES: dict[str, np.dtype[Any]] = {
    "float32": np.dtype("<f4"),
    "float64": np.dtype("<f8"),
    "int32": np.dtype("<i4"),
    "int64": np.dtype("<i8"),
    "uint8": np.dtype("u1"),
    "bool": np.dtype("?"),
}
TYPED_ARRAY_KEYS = frozenset({"dtype", "shape", "data"})
MAX_ARRAY_ELEMENTS = 200_000 * 3 * 2  # the largest request array with margin (points and targets)

_KIND_DTYPES = {"float": np.float64, "int": np.int64, "bool": np.bool_}


def is_typed_array(value: object) -> bool:
    """Whether ``value`` is a typed-binary array map (``dtype``, ``shape``, ``data``)."""
    return isinstance(value, dict) and set(value) == TYPED_ARRAY_KEYS


def encode_typed(array: np.ndarray) -> dict[str, Any]:
    """Encode a numpy array as a typed-binary map for msgpack.

    Args:
        array: any array whose dtype is (or safely casts to) one of `WIRE_DTYPES`.

    Returns:
        ``{"dtype", "shape", "data"}`` with little-endian C-order bytes.
    """
    name = _wire_name(array.dtype)
    contiguous = np.ascontiguousarray(array, dtype=WIRE_DTYPES[name])
    return {"dtype": name, "shape": list(contiguous.shape), "data": contiguous.tobytes()}


def decode_typed(value: dict[str, Any], max_elements: int = MAX_ARRAY_ELEMENTS) -> np.ndarray:
    """Decode a typed-binary map into a numpy array, checking every field.

    Raises:
        ValueError: unknown dtype, bad shape, size mismatch or too many elements.
    """
    name, shape, data = value["dtype"], value["shape"], value["data"]
    if not isinstance(name, str) or name not in WIRE_DTYPES:
        raise ValueError(f"dtype {name!r} is not allowed; use one of {sorted(WIRE_DTYPES)}")
    if not isinstance(shape, list | tuple) or not all(
        isinstance(d, int) and not isinstance(d, bool) and d >= 0 for d in shape
    ):
        raise ValueError("shape must be a list of non-negative integers")
    if not isinstance(data, bytes | bytearray | memoryview):
        raise ValueError("data must be bytes")
    count = math.prod(shape)
    if count > max_elements:
        raise ValueError(f"array has {count} elements, more than the limit of {max_elements}")
    dtype = WIRE_DTYPES[name]
    if count * dtype.itemsize != len(data):
        raise ValueError(
            f"shape {list(shape)} × {dtype.itemsize} bytes needs {count * dtype.itemsize} bytes, got {len(data)}"
        )
    return np.frombuffer(bytes(data), dtype=dtype).reshape(shape).copy()


def _wire_name(dtype: np.dtype[Any]) -> str:
    if dtype == np.bool_:
        return "bool"
    for name, wire in WIRE_DTYPES.items():
        if dtype.kind == wire.kind and dtype.itemsize == wire.itemsize:
            return name
    raise ValueError(f"dtype {dtype} cannot go on the wire; use one of {sorted(WIRE_DTYPES)}")


def _shape_text(shape: Sequence[int | str | None]) -> str:
    inner = ", ".join("*" if d is None else str(d) for d in shape)
    return f"({inner},)" if len(shape) == 1 else f"({inner})"


@dataclass(frozen=True)
class ArraySpec:
    """Constraints of one array field.

    Attributes:
        shape: expected shape; an ``int`` is fixed, a ``str`` names a size shared with other fields
            (e.g. ``"N"``, checked by the enclosing model), ``None`` is free.
        kind: ``"float"`` (stored float64), ``"int"`` (int64) or ``"bool"``.
        finite: reject NaN and ±inf.
    """

    shape: tuple[int | str | None, ...]
    kind: str = "float"
    finite: bool = True

    def validate(self, value: Any) -> np.ndarray:
        """Turn a list, typed-binary map or array into a checked numpy array."""
        if is_typed_array(value):
            array = decode_typed(value)
        elif isinstance(value, np.ndarray):
            array = value
        elif isinstance(value, list | tuple):
            try:
                array = np.asarray(value)
            except ValueError as exc:
                raise ValueError("nested lists are ragged (rows of different lengths)") from exc
        else:
            raise ValueError(f"expected an array (nested lists or typed binary), got {type(value).__name__}")
        if array.dtype == object or array.dtype.kind not in "biuf":
            raise ValueError("array must hold numbers (nested lists of equal length)")
        if array.ndim != len(self.shape):
            raise ValueError(f"expected shape {_shape_text(self.shape)}, got {tuple(array.shape)}")
        for axis, (want, got) in enumerate(zip(self.shape, array.shape, strict=True)):
            if isinstance(want, int) and want != got:
                raise ValueError(f"expected shape {_shape_text(self.shape)}, got {tuple(array.shape)} (axis {axis})")
        if self.kind == "bool":
            if array.dtype.kind == "f" and not np.all(np.isfinite(array)):
                raise ValueError("values must be 0 or 1, found NaN or inf")
            if array.dtype != np.bool_ and not np.all((array == 0) | (array == 1)):
                raise ValueError("values must be 0 or 1")
            return array.astype(np.bool_)
        if self.kind == "int":
            if array.dtype.kind == "f" and not np.all(np.mod(array, 1) == 0):
                raise ValueError("values must be integers")
            return array.astype(np.int64)
        out = array.astype(np.float64)
        if self.finite and not np.all(np.isfinite(out)):
            bad = np.argwhere(~np.isfinite(out))[0].tolist()
            raise ValueError(f"NaN or inf at index {bad}")
        return out

    def json_schema(self) -> dict[str, Any]:
        """JSON schema of the nested-list form (the typed-binary form is msgpack-only)."""
        item: dict[str, Any] = {"boolean": {"type": "boolean"}, "int": {"type": "integer"}}.get(
            self.kind, {"type": "number"}
        )
        if self.kind == "bool":
            item = {"anyOf": [{"type": "boolean"}, {"type": "integer", "enum": [0, 1]}]}
        for dim in reversed(self.shape):
            node: dict[str, Any] = {"type": "array", "items": item}
            if isinstance(dim, int):
                node["minItems"] = node["maxItems"] = dim
            item = node
        item["description"] = f"array of shape {_shape_text(self.shape)}"
        return item

    def __get_pydantic_core_schema__(self, source: Any, handler: GetCoreSchemaHandler) -> core_schema.CoreSchema:
        def serialize(array: np.ndarray, info: core_schema.SerializationInfo) -> Any:
            return array.tolist() if info.mode_is_json() else array

        return core_schema.no_info_plain_validator_function(
            self.validate,
            serialization=core_schema.plain_serializer_function_ser_schema(serialize, info_arg=True),
        )

    def __get_pydantic_json_schema__(
        self, schema: core_schema.CoreSchema, handler: GetJsonSchemaHandler
    ) -> JsonSchemaValue:
        return self.json_schema()


def spec(*shape: int | str | None, kind: str = "float", finite: bool = True) -> ArraySpec:
    """Constraints of an array field: ``Annotated[np.ndarray, spec("N", 3)]`` is an (N, 3) float array."""
    if kind not in _KIND_DTYPES:
        raise ValueError(f"kind must be one of {sorted(_KIND_DTYPES)}")
    return ArraySpec(tuple(shape), kind=kind, finite=finite)
