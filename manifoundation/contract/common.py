"""Base model and shared field types of the wire contract."""

from __future__ import annotations

from typing import Annotated, Any

import numpy as np
from pydantic import AfterValidator, BaseModel, ConfigDict, ValidationInfo, model_validator

from manifoundation.contract.arrays import spec

MIN_POINTS = 64
MAX_POINTS = 200_000
SCHEMA_VERSION = "v1"
IGNORE_UNKNOWN = "ignore_unknown_fields"
"""Validation context key: ``model_validate(data, context={IGNORE_UNKNOWN: True})`` drops fields this contract does
not know, at every level, instead of refusing them. The SDK reads answers so, since a newer minor version of the
contract may add answer fields (docs/compatibility.md); the service never does: an unknown request field is an
error naming it."""
ANSWER_CONTEXT = {IGNORE_UNKNOWN: True}
"""The validation context of answers read by a client."""


class WireModel(BaseModel):
    """Base of every wire schema: unknown fields are errors (unless `IGNORE_UNKNOWN`), arrays are numpy."""

    model_config = ConfigDict(extra="forbid", arbitrary_types_allowed=True, frozen=False)

    @model_validator(mode="before")
    @classmethod
    def _drop_unknown_fields(cls, data: Any, info: ValidationInfo) -> Any:
        if isinstance(data, dict) and info.context and info.context.get(IGNORE_UNKNOWN):
            return {key: value for key, value in data.items() if key in cls.model_fields}
        return data


def _unit_quaternion(q: np.ndarray) -> np.ndarray:
    norm = float(np.linalg.norm(q))
    if norm < 1e-9:
        raise ValueError("quaternion has zero norm")
    return q if abs(norm - 1) < 1e-12 else q / norm


def _nonzero_vector(v: np.ndarray) -> np.ndarray:
    norm = float(np.linalg.norm(v))
    if norm < 1e-9:
        raise ValueError("vector has zero length")
    return v if abs(norm - 1) < 1e-12 else v / norm


Vec3 = Annotated[np.ndarray, spec(3)]
Vec6 = Annotated[np.ndarray, spec(6)]
# Quaternion (w, x, y, z); normalised on input.
Quaternion = Annotated[np.ndarray, spec(4), AfterValidator(_unit_quaternion)]
# A direction (axis); normalised on input.
UnitVec3 = Annotated[np.ndarray, spec(3), AfterValidator(_nonzero_vector)]
# Per-point arrays: N rows, N shared with the object's points (checked by the enclosing model).
Points = Annotated[np.ndarray, spec("N", 3)]
Mask = Annotated[np.ndarray, spec("N", kind="bool")]
PerPoint = Annotated[np.ndarray, spec("N")]
# Per-contact arrays: H rows.
Rows3 = Annotated[np.ndarray, spec("H", 3)]
Vector = Annotated[np.ndarray, spec("D")]
Faces = Annotated[np.ndarray, spec("F", 3, kind="int")]
