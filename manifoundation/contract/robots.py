"""Robot hands: a built-in name, a registered id, or an inline URDF; registration of a URDF/MJCF (+ meshes)."""

from __future__ import annotations

import base64
import binascii
from typing import Annotated

import numpy as np
from pydantic import AfterValidator, BeforeValidator, Field, PlainSerializer, SerializationInfo, model_validator

from manifoundation.contract.arrays import spec
from manifoundation.contract.common import Faces, Points, Rows3, UnitVec3, WireModel

MAX_URDF_BYTES = 2 * 1024 * 1024
"""Largest robot description (URDF or MJCF) in UTF-8 bytes (the science's loader has the same limit)."""
MAX_ARCHIVE_BYTES = 16 * 1024 * 1024
"""Largest hand archive (zip or tar of a description and its meshes), compressed."""
HAND_NAME_PATTERN = r"^[a-z0-9][a-z0-9_\-]{0,63}$"
LINK_NAME = r"^[^\x00-\x1f]{1,128}$"


def _archive_in(value: object) -> bytes:
    """msgpack carries the bytes as they are; JSON carries them base64-encoded."""
    if isinstance(value, (bytes, bytearray, memoryview)):
        return bytes(value)
    if isinstance(value, str):
        if len(value) > 4 * MAX_ARCHIVE_BYTES // 3 + 4:
            raise ValueError(f"over the {MAX_ARCHIVE_BYTES}-byte archive limit")
        try:
            return base64.b64decode(value, validate=True)
        except (binascii.Error, ValueError) as exc:
            raise ValueError("not valid base64 (JSON bodies carry the archive base64-encoded)") from exc
    raise ValueError("expected bytes (msgpack) or a base64 string (JSON)")


def _archive_out(value: bytes, info: SerializationInfo) -> bytes | str:
    return base64.b64encode(value).decode() if info.mode == "json" else value


ArchiveBytes = Annotated[
    bytes,
    BeforeValidator(_archive_in),
    PlainSerializer(_archive_out, return_type=bytes | str),
    Field(json_schema_extra={"type": "string", "format": "base64"}),
]


def _description_bytes(value: str | None) -> str | None:
    """A description's limit is in UTF-8 bytes (``max_length`` alone counts characters)."""
    if value is not None and len(value.encode()) > MAX_URDF_BYTES:
        raise ValueError(f"{len(value.encode())} bytes, over the {MAX_URDF_BYTES}-byte limit")
    return value


Description = Annotated[str, AfterValidator(_description_bytes)]


class RobotIn(WireModel):
    """Which hand to use: exactly one of ``name`` (built-in or registered) or ``urdf`` (+ ``fingertips``)."""

    name: str | None = Field(None, pattern=HAND_NAME_PATTERN, examples=["leap"])
    urdf: Description | None = Field(None, max_length=MAX_URDF_BYTES, description="Inline URDF XML (untrusted).")
    fingertips: list[str] | None = Field(None, min_length=1, max_length=8)
    tip_offsets: Rows3 | None = None

    @model_validator(mode="after")
    def _one_source(self) -> RobotIn:
        if (self.name is None) == (self.urdf is None):
            raise ValueError("robot: give exactly one of 'name' or 'urdf'")
        if self.urdf is not None and not self.fingertips:
            raise ValueError("fingertips: required with an inline urdf")
        if self.name is not None and (self.fingertips or self.tip_offsets is not None):
            raise ValueError("fingertips: only with an inline urdf (a named hand has its own)")
        if self.tip_offsets is not None and self.fingertips and len(self.tip_offsets) != len(self.fingertips):
            raise ValueError("tip_offsets: one row per fingertip")
        return self


class RobotRegister(WireModel):
    """Body of ``POST /v1/robots``: exactly one of ``archive`` (a zip/tar with a URDF or MJCF and its meshes),
    ``urdf`` or ``mjcf`` (the description alone, primitives only)."""

    name: str = Field(..., pattern=HAND_NAME_PATTERN)
    urdf: Description | None = Field(None, min_length=1, max_length=MAX_URDF_BYTES)
    mjcf: Description | None = Field(None, min_length=1, max_length=MAX_URDF_BYTES)
    archive: ArchiveBytes | None = Field(
        None,
        max_length=MAX_ARCHIVE_BYTES,
        description="zip or tar (gz/bz2/xz): the description and its meshes (base64 in JSON, bytes in msgpack).",
        json_schema_extra={"maxLength": 4 * MAX_ARCHIVE_BYTES // 3 + 4},
    )
    description: str | None = Field(
        None, max_length=300, description="The archive member to load (default: its only URDF, else its top MJCF)."
    )
    palm: str | None = Field(
        None, pattern=LINK_NAME, description="Link the floating base attaches to; the sub-tree below it is the hand."
    )
    fingertips: list[str] | None = Field(
        None, min_length=1, max_length=8, description="Fingertip links (default: the sub-tree's leaf links)."
    )
    tip_offsets: Rows3 | None = None
    rest: dict[str, float] | None = Field(None, max_length=64, description="Free joint -> rest value.")
    approach_axis: UnitVec3 | None = None

    @model_validator(mode="after")
    def _one_source(self) -> RobotRegister:
        given = [k for k in ("archive", "urdf", "mjcf") if getattr(self, k) is not None]
        if len(given) != 1:
            raise ValueError(f"give exactly one of 'archive', 'urdf' or 'mjcf' (got {', '.join(given) or 'none'})")
        if self.tip_offsets is not None and (not self.fingertips or len(self.tip_offsets) != len(self.fingertips)):
            raise ValueError("tip_offsets: one row per fingertip (name the fingertips)")
        if self.description is not None and self.archive is None:
            raise ValueError("description: only with an archive")
        return self

    @property
    def stored_bytes(self) -> int:
        """What the registration occupies in the store (description and archive)."""
        return len(self.archive or b"") + len((self.urdf or self.mjcf or "").encode())


class RobotPreview(WireModel):
    """The hand at rest in its palm frame: coarse collision meshes, spheres, pad samples, fingertip points."""

    vertices: Points
    faces: Faces
    spheres: Annotated[np.ndarray, spec("S", 4)]
    pads: Points
    tips: Rows3


class RobotPublic(WireModel):
    """A hand as the service describes it."""

    name: str
    builtin: bool
    dof: int = Field(..., description="Finger joints (the palm adds 6).")
    joint_names: list[str]
    lower: list[float]
    upper: list[float]
    fingertips: list[str]
    num_spheres: int | None = None
    source: str | None = Field(None, description="Where the description comes from (package or 'user').")
    warnings: list[str] = Field(
        default_factory=list, description="What of a registered URDF was not used (e.g. mesh files: never read)."
    )
    palm: str | None = Field(None, description="The link the floating 6-DoF base attaches to.")
    format: str | None = Field(None, description="'urdf' or 'mjcf' (registered hands).")
    surface_points: int | None = Field(None, description="Points of the hand cloud the network sees.")
    pad_area_cm2: list[float] | None = Field(None, description="Per fingertip: its contact pad's mesh area.")
    couplings: list[str] = Field(default_factory=list, description="Mimic/tendon/equality couplings: honoured or free.")
    ignored: list[str] = Field(default_factory=list, description="What of the upload was not used, and why.")
    meshes: int | None = Field(None, description="Mesh files read from the archive.")
    registration_s: float | None = Field(None, description="Seconds the worker took to build the hand.")
    stored_bytes: int | None = Field(None, description="Bytes the registration occupies (counts to the key's quota).")
    view_url: str | None = Field(None, description="Page drawing the hand at rest with its spheres and pads.")
    preview: RobotPreview | None = Field(None, description="Data of the view page (only from .../preview).")
