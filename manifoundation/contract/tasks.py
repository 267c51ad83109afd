"""What the manipulation should achieve: a motion, a wrench, or "hold it" (force closure)."""

from __future__ import annotations

from typing import Annotated, Literal

import numpy as np
from pydantic import ConfigDict, Field, model_validator
from pydantic.config import JsonDict

from manifoundation.contract.common import Points, Quaternion, Vec3, Vec6, WireModel


def _kind_required(schema: JsonDict) -> None:
    """``kind`` is the union's discriminator: a body must name it, whatever the Python default."""
    required = schema.setdefault("required", [])
    if isinstance(required, list) and "kind" not in required:
        required.insert(0, "kind")


KIND_REQUIRED = ConfigDict(json_schema_extra=_kind_required)


class DeltaPoseTask(WireModel):
    """Move the object rigidly: translate by ``translation`` (m) and rotate by ``rotation`` about its centre."""

    model_config = KIND_REQUIRED

    kind: Literal["delta_pose"] = "delta_pose"
    translation: Vec3 = Field(default_factory=lambda: np.zeros(3))
    rotation: Quaternion = Field(default_factory=lambda: np.array([1.0, 0, 0, 0]))

    @model_validator(mode="after")
    def _moves(self) -> DeltaPoseTask:
        still = np.linalg.norm(self.translation) < 1e-9 and abs(abs(self.rotation[0]) - 1) < 1e-12
        if still:
            raise ValueError("delta pose is the identity: nothing to do (use force_closure to hold the object)")
        return self


class PointMotionTask(WireModel):
    """Per-point target motion M (N, 3), metres; for deformables the motion each point should make."""

    model_config = KIND_REQUIRED

    kind: Literal["point_motion"] = "point_motion"
    motion: Points


class TargetPointsTask(WireModel):
    """The object's target point cloud: (N, 3) point-to-point with the input points, or with
    ``correspondence="unknown"`` an (M, 3) cloud in any order (the per-point motion is then registered)."""

    model_config = KIND_REQUIRED

    kind: Literal["target_points"] = "target_points"
    targets: Points
    correspondence: Literal["index", "unknown"] = Field(
        "index", description="'index': targets[i] is where point i goes; 'unknown': an unordered target cloud."
    )


class WrenchTask(WireModel):
    """A target wrench (force N, torque N·m) about the object's centre of mass, world frame."""

    model_config = KIND_REQUIRED

    kind: Literal["wrench"] = "wrench"
    wrench: Vec6

    @model_validator(mode="after")
    def _nonzero(self) -> WrenchTask:
        if np.linalg.norm(self.wrench) < 1e-12:
            raise ValueError("wrench: zero wrench; use force_closure to hold the object")
        return self


class ForceClosureTask(WireModel):
    """Hold the object: a grasp that can resist any wrench (w = 0, f ≠ 0)."""

    model_config = KIND_REQUIRED

    kind: Literal["force_closure"] = "force_closure"


class JointMotionTask(WireModel):
    """Articulated objects: move the joint by ``delta`` (rad for revolute, m for prismatic)."""

    model_config = KIND_REQUIRED

    kind: Literal["joint_motion"] = "joint_motion"
    delta: float = Field(..., description="Signed joint displacement.")

    @model_validator(mode="after")
    def _nonzero(self) -> JointMotionTask:
        if self.delta == 0 or not np.isfinite(self.delta):
            raise ValueError("delta: must be finite and non-zero")
        return self


TaskIn = Annotated[
    DeltaPoseTask | PointMotionTask | TargetPointsTask | WrenchTask | ForceClosureTask | JointMotionTask,
    Field(discriminator="kind"),
]
TASK_KINDS: tuple[str, ...] = tuple(
    str(task.model_fields["kind"].default)
    for task in (DeltaPoseTask, PointMotionTask, TargetPointsTask, WrenchTask, ForceClosureTask, JointMotionTask)
)
"""The ``kind`` tag of every task in `TaskIn`, in its order: the one list of task kinds."""
