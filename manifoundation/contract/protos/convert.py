"""The one conversion between the `manifoundation.v1` messages and the pydantic contract (`manifoundation.contract`).

The proto side only converts; the pydantic models validate, so a gRPC request is checked by exactly the code that
checks an HTTP one and a bad field is named the same way (``object.points: ...``). The proto mirrors the contract
field for field (`tests/api/grpc/test_convert.py` holds them together), so the conversion walks descriptors
instead of listing fields:

- an ``Array`` message becomes the msgpack typed-binary map ``{dtype, shape, data}``, which the contract's array
  fields decode with the same dtype whitelist and byte-length rule (`manifoundation.contract.arrays.decode_typed`); the
  other way an ndarray is encoded with `manifoundation.contract.arrays.encode_typed`;
- a message with a ``kind`` oneof (``TaskIn``) is the contract's discriminated union: the chosen field's name is
  ``kind`` and its message's fields sit beside it;
- an unset message, an unset ``optional`` scalar and an empty repeated field are left out, so the contract's
  defaults apply; a plain proto3 scalar is always present (its zero value included), as proto3 defines it. In an
  answer (``answer=True``: a result, a job, a hand, which the service fills completely) an empty repeated field is
  an empty list, since proto3 cannot tell "empty" from "unset";
- a ``map<string, ...>`` is a dict; enumerations are their contract strings.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, TypeVar

import numpy as np
from google.protobuf.descriptor import Descriptor, FieldDescriptor
from google.protobuf.message import Message

from manifoundation.contract import WireModel
from manifoundation.contract.arrays import encode_typed

ARRAY = "manifoundation.v1.Array"
UNION = "kind"  # the oneof that carries a discriminated union of the contract

ModelT = TypeVar("ModelT", bound=WireModel)
MessageT = TypeVar("MessageT", bound=Message)


def from_proto(message: Message, model: type[ModelT], *, answer: bool = False) -> ModelT:
    """Validate ``message`` as the contract's ``model`` (``answer``: a complete answer, see the module doc).

    Raises:
        pydantic.ValidationError: the contract's own errors, naming each field by its path.
    """
    return model.model_validate(to_data(message, answer=answer))


def to_proto(value: WireModel, message: type[MessageT]) -> MessageT:
    """The contract object ``value`` as a ``message`` (arrays as typed bytes, None left unset)."""
    out = message()
    fill(out, value.model_dump(mode="python", exclude_none=True))
    return out


def to_data(message: Message, *, answer: bool = False) -> dict[str, Any]:
    """Plain data for ``model_validate``: what the sender set, arrays as typed-binary maps."""
    descriptor: Descriptor = message.DESCRIPTOR
    if UNION in descriptor.oneofs_by_name:
        chosen = message.WhichOneof(UNION)
        return {} if chosen is None else {UNION: chosen, **to_data(getattr(message, chosen), answer=answer)}
    data: dict[str, Any] = {}
    for field in descriptor.fields:
        value = getattr(message, field.name)
        if _is_map(field):
            if value or answer:
                data[field.name] = dict(value)
        elif field.is_repeated:
            if value or answer:
                data[field.name] = [_read(field, item, answer) for item in value]
        elif field.message_type is not None or field.has_presence:
            if message.HasField(field.name):
                data[field.name] = _read(field, value, answer)
        else:
            data[field.name] = value
    return data


def fill(message: Message, data: Mapping[str, Any]) -> None:
    """Set ``message``'s fields from plain data (a ``model_dump``), recursively; None values stay unset.

    Raises:
        KeyError: ``data`` names a field the message does not have (the proto is behind the contract).
    """
    descriptor: Descriptor = message.DESCRIPTOR
    if UNION in descriptor.oneofs_by_name:
        rest = dict(data)
        chosen = getattr(message, str(rest.pop(UNION)))
        chosen.SetInParent()
        fill(chosen, rest)
        return
    for name, value in data.items():
        if value is None:
            continue
        field = descriptor.fields_by_name[name]
        target = getattr(message, name)
        if _is_map(field):
            value_field = field.message_type.fields_by_name["value"]
            target.update({str(k): _scalar(value_field, v) for k, v in value.items()})
        elif field.is_repeated and field.message_type is None:
            items = value.tolist() if isinstance(value, np.ndarray) else value
            target.extend(_scalar(field, item) for item in items)
        elif field.is_repeated:
            for item in value:
                _write(target.add(), item)
        elif field.message_type is not None:
            _write(target, value)
        else:
            setattr(message, name, _scalar(field, value))


def _read(field: FieldDescriptor, value: Any, answer: bool) -> Any:
    if field.message_type is None:
        return value
    if field.message_type.full_name == ARRAY:
        return {"dtype": value.dtype, "shape": list(value.shape), "data": value.data}
    return to_data(value, answer=answer)


def _write(message: Message, value: Any) -> None:
    message.SetInParent()
    if message.DESCRIPTOR.full_name == ARRAY:
        typed = encode_typed(np.asarray(value))
        message.dtype, message.data = typed["dtype"], typed["data"]
        message.shape.extend(typed["shape"])
    else:
        fill(message, value)


def _is_map(field: FieldDescriptor) -> bool:
    return field.message_type is not None and field.message_type.GetOptions().map_entry


def _scalar(field: FieldDescriptor, value: Any) -> Any:
    """A Python value of the field's type (numpy scalars and StrEnum members become plain values)."""
    kind = field.cpp_type
    if kind == FieldDescriptor.CPPTYPE_STRING:
        return value if isinstance(value, bytes) else str(value)
    if kind == FieldDescriptor.CPPTYPE_BOOL:
        return bool(value)
    if kind in (FieldDescriptor.CPPTYPE_DOUBLE, FieldDescriptor.CPPTYPE_FLOAT):
        return float(value)
    return int(value)
