"""Tasks: a delta pose (quaternion, rotation matrix or 4×4 transform), a target point cloud, a wrench, or "hold it"."""

from __future__ import annotations

from typing import Any

import numpy as np
import pydantic

from manifoundation.contract import DeltaPoseTask, ForceClosureTask, TargetPointsTask, TaskIn, WrenchTask
from manifoundation.sdk.errors import checked, local_validation_error

TaskLike = TaskIn | str | dict[str, Any]
_TASK_ADAPTER: pydantic.TypeAdapter[Any] = pydantic.TypeAdapter(TaskIn)


def rotation_to_quaternion(rotation: Any) -> np.ndarray:
    """A unit quaternion (w, x, y, z) from a quaternion (4,), a rotation matrix (3, 3) or a transform (4, 4)."""
    r = np.asarray(rotation, dtype=np.float64)
    if r.shape == (4,):
        return r / np.linalg.norm(r)
    if r.shape == (4, 4):
        r = r[:3, :3]
    if r.shape != (3, 3):
        raise ValueError(f"rotation: expected (4,) quaternion, (3, 3) or (4, 4) matrix, got {r.shape}")
    # Shepperd's method: numerically stable for every rotation.
    trace = np.trace(r)
    candidates = [trace, r[0, 0], r[1, 1], r[2, 2]]
    k = int(np.argmax(candidates))
    if k == 0:
        s = 2.0 * np.sqrt(1.0 + trace)
        q = [0.25 * s, (r[2, 1] - r[1, 2]) / s, (r[0, 2] - r[2, 0]) / s, (r[1, 0] - r[0, 1]) / s]
    else:
        i, j, m = [(0, 1, 2), (1, 2, 0), (2, 0, 1)][k - 1]
        s = 2.0 * np.sqrt(1.0 + r[i, i] - r[j, j] - r[m, m])
        q = [0.0, 0.0, 0.0, 0.0]
        q[0] = (r[m, j] - r[j, m]) / s
        q[1 + i] = 0.25 * s
        q[1 + j] = (r[j, i] + r[i, j]) / s
        q[1 + m] = (r[m, i] + r[i, m]) / s
    out = np.asarray(q)
    return out / np.linalg.norm(out) * (1.0 if out[0] >= 0 else -1.0)


def delta_pose(translation: Any = (0.0, 0.0, 0.0), rotation: Any = None) -> DeltaPoseTask:
    """Move the object rigidly by ``translation`` (m) and ``rotation`` about its centre.

    Args:
        translation: (3,) metres; or a (4, 4) homogeneous transform (then ``rotation`` is taken from it).
        rotation: (4,) quaternion (w, x, y, z), or a (3, 3) rotation matrix; identity when None.
    """
    t = np.asarray(translation, dtype=np.float64)
    if t.shape == (4, 4):
        t, rotation = t[:3, 3], t[:3, :3] if rotation is None else rotation
    q = np.array([1.0, 0.0, 0.0, 0.0]) if rotation is None else rotation_to_quaternion(rotation)
    return checked(DeltaPoseTask, "task", translation=t, rotation=q)


def target_points(targets: Any) -> TargetPointsTask:
    """Move each object point to its row of ``targets`` (N, 3), point-to-point with the object's points."""
    return checked(TargetPointsTask, "task", targets=np.asarray(targets, dtype=np.float64))


def force_closure() -> ForceClosureTask:
    """Hold the object: a grasp that resists any wrench."""
    return ForceClosureTask()


def wrench(force: Any = (0.0, 0.0, 0.0), torque: Any = (0.0, 0.0, 0.0)) -> WrenchTask:
    """Apply ``force`` (N) and ``torque`` (N·m) about the object's centre of mass, world frame."""
    return checked(WrenchTask, "task", wrench=np.concatenate([np.asarray(force), np.asarray(torque)]))


def as_task(value: TaskLike) -> TaskIn:
    """Coerce a task model, a dict with ``kind``, or the string ``"force_closure"`` into a task."""
    if isinstance(value, str):
        value = {"kind": value}
    if isinstance(value, dict):
        try:
            return _TASK_ADAPTER.validate_python(value)
        except pydantic.ValidationError as exc:
            raise local_validation_error(exc, "task") from exc
    return value
