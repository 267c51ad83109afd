"""Target wrenches (paper Eq. 4-5), the joint-space projection P^J, and the residual's task description.

Wrench convention: a wrench is ``[F; τ]`` about the object's centre ``c`` (its centre of mass). Inside the
refinement wrenches are *scaled*: ``[F; τ / ρ]`` with ρ the object's characteristic length (largest distance of a
surface point from ``c``), so force and torque rows are of the same order for any object size; a unit target
wrench and contact forces with normal components ≤ 1 then make sense for 5 cm and 40 cm objects alike.

Inverse dynamics: the paper writes ``ŵ = 2/Δt² [Δx / M; Δθ / I]``; we use the physical ``ŵ = 2/Δt² [M Δx;
I Δθ]`` (F = M a, τ = I α for a motion from rest over Δt), since ``Δx / M`` is not a force and makes heavy
objects want *more* acceleration per newton. After normalisation only the direction matters and density cancels.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation


@dataclass(frozen=True)
class WrenchTask:
    """What the contact forces must produce: ``r = projection @ Σ G_i f_i − target`` (scaled wrenches).

    Attributes:
        projection: (k, 6) rows applied to the scaled object wrench; identity for a free rigid object, P^J (1, 6)
            for an articulated joint.
        target: (k,) target in the projected space; zeros for force closure.
        centre: (3,) point the wrench is taken about (object centre of mass).
        length: ρ, the torque scale in metres.
        closure: force closure: ``target = 0`` with the normalisation Σ_i f_i·(−n_i) = 1 that excludes f = 0.
    """

    projection: np.ndarray
    target: np.ndarray
    centre: np.ndarray
    length: float
    closure: bool = False

    @property
    def rows(self) -> int:
        """k, the residual's dimension."""
        return int(self.projection.shape[0])


def characteristic_length(points: np.ndarray, centre: np.ndarray) -> float:
    """ρ = the largest distance of a point from ``centre`` (at least 1 mm)."""
    return max(float(np.max(np.linalg.norm(points - centre, axis=1))), 1e-3)


def normalise(w: np.ndarray) -> np.ndarray:
    """``w / ‖w‖`` (Eq. 5).

    Raises:
        ValueError: a zero or non-finite wrench (use force closure for "hold it").
    """
    norm = float(np.linalg.norm(w))
    if not np.isfinite(norm) or norm < 1e-12:
        raise ValueError("target wrench must be finite and non-zero; use force closure for w = 0")
    return np.asarray(w, dtype=np.float64) / norm


def wrench_from_motion(
    delta_x: np.ndarray, delta_theta: np.ndarray, mass: float, inertia: np.ndarray, dt: float = 1.0
) -> np.ndarray:
    """Unscaled wrench ``ŵ = 2/Δt² [M Δx; I Δθ]`` that moves a body at rest by (Δx, Δθ) in Δt (Eq. 4).

    Args:
        delta_x: (3,) translation of the centre of mass (m).
        delta_theta: (3,) rotation vector (rad), about the centre of mass.
        mass: M (kg).
        inertia: (3, 3) inertia tensor about the centre of mass (kg m²).
        dt: Δt (s); only scales the result.
    """
    return 2.0 / dt**2 * np.concatenate([mass * np.asarray(delta_x), np.asarray(inertia) @ delta_theta])


def motion_from_pose(
    rotation: np.ndarray, translation: np.ndarray, centre: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """(Δx, Δθ) of the centre of mass for the rigid motion ``x ↦ R x + t``."""
    centre = np.asarray(centre, dtype=np.float64)
    delta_x = np.asarray(rotation) @ centre + np.asarray(translation) - centre
    return delta_x, Rotation.from_matrix(np.asarray(rotation)).as_rotvec()


def kabsch(source: np.ndarray, target: np.ndarray, weights: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Weighted least-squares rigid motion (R, t) with ``R @ source_i + t ≈ target_i``."""
    w = np.ones(len(source)) if weights is None else np.asarray(weights, dtype=np.float64)
    w = w / w.sum()
    mu_s, mu_t = w @ source, w @ target
    h = ((source - mu_s) * w[:, None]).T @ (target - mu_t)
    u, _, vt = np.linalg.svd(h)
    d = np.sign(np.linalg.det(vt.T @ u.T)) or 1.0
    rot = vt.T @ np.diag([1.0, 1.0, d]) @ u.T
    return rot, mu_t - rot @ mu_s


def rigid_task(wrench: np.ndarray, centre: np.ndarray, length: float) -> WrenchTask:
    """Task for a free rigid object: the scaled wrench ``[F; τ/ρ]`` normalised to unit length."""
    w = np.asarray(wrench, dtype=np.float64)
    scaled = normalise(np.concatenate([w[:3], w[3:] / length]))
    return WrenchTask(np.eye(6), scaled, np.asarray(centre, dtype=np.float64), float(length))


def closure_task(centre: np.ndarray, length: float) -> WrenchTask:
    """Force-closure task: w = 0 with the normalisation Σ f_n = 1."""
    return WrenchTask(np.eye(6), np.zeros(6), np.asarray(centre, dtype=np.float64), float(length), closure=True)


def joint_projection(joint_type: str, axis: np.ndarray, origin: np.ndarray) -> np.ndarray:
    """P^J (1, 6) on *unscaled* wrenches about the world origin.

    Revolute joint (axis a through o): ``[(o × a)ᵀ, aᵀ]`` = torque about the axis. Prismatic: ``[aᵀ, 0]``.

    Raises:
        ValueError: unknown joint type or zero axis.
    """
    a = np.asarray(axis, dtype=np.float64)
    if np.linalg.norm(a) < 1e-12:
        raise ValueError("joint axis must be non-zero")
    a = a / np.linalg.norm(a)
    if joint_type == "revolute":
        return np.concatenate([np.cross(np.asarray(origin, dtype=np.float64), a), a])[None, :]
    if joint_type == "prismatic":
        return np.concatenate([a, np.zeros(3)])[None, :]
    raise ValueError(f"joint type must be 'revolute' or 'prismatic', got {joint_type!r}")


def articulated_task(
    joint_type: str,
    axis: np.ndarray,
    origin: np.ndarray,
    centre: np.ndarray,
    length: float,
    effort: float = 1.0,
) -> WrenchTask:
    """Joint-space task r^J = P^J(Σ G_i f_i) − τ (paper §III-B), with τ = ``effort`` in scaled units.

    The scaled wrench about ``centre`` is ``[F; τ_c/ρ]``; P^J is re-expressed on it, and for a revolute joint
    divided by ρ so that τ is a torque over ρ (a unit normal force at lever arm ρ gives 1); the sign of
    ``effort`` picks the direction (positive: along +axis by the right-hand rule / translation along +axis).
    """
    c = np.asarray(centre, dtype=np.float64)
    p = joint_projection(joint_type, axis, origin)[0]
    # wrench about the world origin from one about c: F' = F, τ' = τ_c + c × F
    to_origin = np.block([[np.eye(3), np.zeros((3, 3))], [_skew(c), np.eye(3)]])
    unscale = np.diag([1.0, 1.0, 1.0, length, length, length])
    row = p @ to_origin @ unscale
    if joint_type == "revolute":
        row = row / length
    return WrenchTask(row[None, :], np.array([float(effort)]), c, float(length))


def _skew(v: np.ndarray) -> np.ndarray:
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])
