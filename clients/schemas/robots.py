"""Robot hands: a built-in name, a registered id, or an inline URDF."""

from __future__ import annotations

from pydantic import Field, model_validator

from clients.schemas.common import Rows3, WireModel

MAX_URDF_BYTES = 2 * 1024 * 1024
HAND_NAME_PATTERN = r"^[a-z0-9][a-z0-9_\-]{0,63}$"


class RobotIn(WireModel):
    """Which hand to use: exactly one of ``name`` (built-in or registered) or ``urdf`` (+ ``fingertips``)."""

    name: str | None = Field(None, pattern=HAND_NAME_PATTERN, examples=["leap"])
    urdf: str | None = Field(None, max_length=MAX_URDF_BYTES, description="Inline URDF XML (untrusted).")
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
    """Body of ``POST /v1/robots``."""

    name: str = Field(..., pattern=HAND_NAME_PATTERN)
    urdf: str = Field(..., min_length=1, max_length=MAX_URDF_BYTES)
    fingertips: list[str] = Field(..., min_length=1, max_length=8)
    tip_offsets: Rows3 | None = None


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
