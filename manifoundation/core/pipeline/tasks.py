"""Turn a task into the refinement's residual (`WrenchTask`) and into the network's per-point motion."""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from manifoundation.core.pipeline.types import InvalidInput, JointInput, TaskInput
from manifoundation.core.refine.wrench import (
    WrenchTask,
    articulated_task,
    characteristic_length,
    closure_task,
    kabsch,
    motion_from_pose,
    rigid_task,
    wrench_from_motion,
)

WRENCH_MOTION_SCALE = 0.05  # m: size of the per-point motion shown to the network for a wrench task


def _rigid_motion(task: TaskInput, points: np.ndarray, centre: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(R, t) of the task's rigid motion, x ↦ R x + t."""
    if task.kind == "delta_pose":
        quat = np.asarray(task.rotation if task.rotation is not None else [1.0, 0, 0, 0], dtype=np.float64)
        rot = Rotation.from_quat(quat[[1, 2, 3, 0]]).as_matrix()
        trans = np.zeros(3) if task.translation is None else np.asarray(task.translation, dtype=np.float64)
        return rot, centre + trans - rot @ centre  # rotation about the centre of mass, then translation
    target = task.targets if task.kind == "target_points" else (
        None if task.motion is None else points + np.asarray(task.motion)
    )
    if target is None or np.shape(target) != points.shape:
        name = "targets" if task.kind == "target_points" else "motion"
        raise InvalidInput(f"task.{name}: expected shape {points.shape}")
    return kabsch(points, np.asarray(target, dtype=np.float64))


def build_task(
    task: TaskInput,
    points: np.ndarray,
    mass: float,
    centre: np.ndarray,
    inertia: np.ndarray,
    joint: JointInput | None = None,
) -> WrenchTask:
    """The refinement residual for ``task`` (Eq. 4-5; joint space for ``joint_motion``).

    Raises:
        InvalidInput: unknown kind, missing or inconsistent fields, or a task that asks for no motion.
    """
    length = characteristic_length(points, centre)
    try:
        if task.kind == "force_closure":
            return closure_task(centre, length)
        if task.kind == "wrench":
            if task.wrench is None or np.shape(task.wrench) != (6,):
                raise InvalidInput("task.wrench: expected 6 values")
            return rigid_task(np.asarray(task.wrench, dtype=np.float64), centre, length)
        if task.kind == "joint_motion":
            if joint is None:
                raise InvalidInput("task: joint_motion needs object.joint")
            if task.delta is None or not np.isfinite(task.delta) or task.delta == 0:
                raise InvalidInput("task.delta: must be finite and non-zero")
            return articulated_task(
                joint.type, joint.axis, joint.origin, centre, length, effort=float(np.sign(task.delta))
            )
        if task.kind in ("delta_pose", "point_motion", "target_points"):
            rot, trans = _rigid_motion(task, points, centre)
            dx, dtheta = motion_from_pose(rot, trans, centre)
            return rigid_task(wrench_from_motion(dx, dtheta, mass, inertia), centre, length)
    except ValueError as exc:
        if isinstance(exc, InvalidInput):
            raise
        raise InvalidInput(f"task: {exc}") from exc
    raise InvalidInput(f"task.kind: unknown kind {task.kind!r}")


def network_motion(
    task: TaskInput, points: np.ndarray, centre: np.ndarray, mass: float, inertia: np.ndarray,
    joint: JointInput | None = None,
) -> np.ndarray:
    """(N, 3) per-point motion the network is conditioned on (zeros for force closure)."""
    n = len(points)
    if task.kind == "force_closure":
        return np.zeros((n, 3))
    if task.kind == "point_motion" and task.motion is not None:
        return np.asarray(task.motion, dtype=np.float64)
    if task.kind == "target_points" and task.targets is not None:
        to_targets: np.ndarray = np.asarray(task.targets, dtype=np.float64) - points
        return to_targets
    if task.kind == "delta_pose":
        rot, trans = _rigid_motion(task, points, centre)
        rigid: np.ndarray = points @ rot.T + trans - points
        return rigid
    if task.kind == "wrench" and task.wrench is not None:
        w = np.asarray(task.wrench, dtype=np.float64)
        dx = w[:3] / mass
        dtheta = np.linalg.solve(inertia, w[3:])
        move = dx[None] + np.cross(dtheta, points - centre)
        scale = np.abs(move).max()
        return move / scale * WRENCH_MOTION_SCALE if scale > 0 else move
    if task.kind == "joint_motion" and joint is not None and task.delta is not None:
        axis = np.asarray(joint.axis, dtype=np.float64) / np.linalg.norm(joint.axis)
        part = np.asarray(joint.part_mask, dtype=bool)
        out = np.zeros((n, 3))
        if joint.type == "prismatic":
            out[part] = axis * task.delta
        else:
            rot = Rotation.from_rotvec(axis * task.delta).as_matrix()
            rel = points[part] - joint.origin
            out[part] = rel @ rot.T - rel
        return out
    return np.zeros((n, 3))


__all__ = ["build_task", "network_motion"]
