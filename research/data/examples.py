"""From a feasible grasp to training examples: forces in friction cones, wrench, motion, labels.

Rigid: forces f_i = a_i (−n_i) + t_i with a_i ~ U(0.1, 1), |t_i| ≤ μ a_i; the scaled wrench w = Σ G_i f_i
(manifoundation.core.refine.grasp) is normalised to unit length by dividing the forces by ‖w‖ (rejected when a normal
force then exceeds 1, the refinement's bound), so the label grasp solves the refinement's force problem exactly.
The target motion is the inverse of Eq. 4 of the unscaled wrench, scaled to a random size.

Articulated: the object is a link on a revolute (hinge on a bounding-box edge) or prismatic joint; the
generalised force τ = P^J Σ G_i f_i (`manifoundation.core.refine.wrench.articulated_task`) gives the motion's direction
(sign) and the forces are scaled so |τ| = 1. The per-point motion is the joint motion of every point.

Motion split: a motion is "unseen" when its unit scaled wrench lies within the cones of `HELD_OUT_MOTIONS`
(8 fixed directions in R^6, cos ≥ ``HELD_OUT_COS``); those never enter training.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from manifoundation.core.refine.grasp import grasp_maps, tangents
from manifoundation.core.refine.wrench import articulated_task, characteristic_length
from research.data.labels import (
    MOTION_SCALE,
    contact_wrench,
    heat_and_force,
    joint_point_motion,
    motion_from_wrench,
    region_mask,
    rigid_point_motion,
    scale_motion,
)

FRICTION = (0.3, 1.0)
FORCE_TRIES = 24
HELD_OUT_COS = 0.75
HELD_OUT_MOTIONS = np.random.default_rng(20240601).normal(size=(8, 6))
HELD_OUT_MOTIONS /= np.linalg.norm(HELD_OUT_MOTIONS, axis=1, keepdims=True)
REVOLUTE_ANGLE = (0.1, 0.5)  # rad
PRISMATIC_SHIFT = (0.05, 0.3)  # fraction of s


def is_unseen_motion(scaled_wrench: np.ndarray) -> bool:
    """Whether a (scaled) wrench direction is in the held-out motion set."""
    w = scaled_wrench / max(np.linalg.norm(scaled_wrench), 1e-12)
    return bool((HELD_OUT_MOTIONS @ w).max() >= HELD_OUT_COS)


@dataclass(frozen=True)
class ObjectInfo:
    """What labels need of an object: network cloud (N, 3) + normals, centre of mass, mass, inertia, s, ρ."""

    points: np.ndarray
    normals: np.ndarray
    centre: np.ndarray
    mass: float
    inertia: np.ndarray
    scale: float
    length: float

    @classmethod
    def from_object(cls, obj: Any, density: float = 500.0) -> ObjectInfo:
        mesh = obj.mesh
        centre = np.asarray(mesh.center_mass, dtype=np.float64)
        return cls(
            points=obj.points,
            normals=obj.normals,
            centre=centre,
            mass=float(mesh.volume * density),
            inertia=np.asarray(mesh.moment_inertia, dtype=np.float64) * density,
            scale=float(np.ptp(obj.points, axis=0).max()),
            length=characteristic_length(obj.points, centre),
        )


def sample_forces(normals: np.ndarray, mu: float, rng: np.random.Generator) -> np.ndarray:
    """(m, 3) random forces inside the friction cones (pushing into the surface)."""
    m = len(normals)
    a = rng.uniform(0.1, 1.0, size=m)
    t1, t2 = tangents(normals)
    ang = rng.uniform(0, 2 * np.pi, size=m)
    mag = mu * a * np.sqrt(rng.uniform(0, 1, size=m))
    forces: np.ndarray = -a[:, None] * normals + mag[:, None] * (np.cos(ang)[:, None] * t1 + np.sin(ang)[:, None] * t2)
    return forces


def _joint(info: ObjectInfo, rng: np.random.Generator) -> tuple[str, np.ndarray, np.ndarray]:
    """A random joint: revolute about a bounding-box edge, or prismatic along a random axis."""
    lo, hi = info.points.min(0), info.points.max(0)
    k = int(rng.integers(3))
    if rng.random() < 0.5:
        axis = np.eye(3)[k]
        origin = np.where(rng.random(3) < 0.5, lo, hi)
        origin[k] = (lo[k] + hi[k]) / 2
        return "revolute", axis, origin
    axis = rng.normal(size=3)
    return "prismatic", axis / np.linalg.norm(axis), info.centre.copy()


def make_example(
    info: ObjectInfo,
    contacts: np.ndarray,
    normals: np.ndarray,
    rng: np.random.Generator,
    *,
    want_unseen: bool,
    articulated: bool,
) -> dict[str, Any] | None:
    """One example's labels for a grasp's contacts, or None when no force sample fits the wanted split."""
    mu = float(rng.uniform(*FRICTION))
    g = grasp_maps(contacts, info.centre, info.length)  # (m, 6, 3)
    joint = _joint(info, rng) if articulated else None
    for _ in range(FORCE_TRIES):
        f = sample_forces(normals, mu, rng)
        w = np.einsum("mij,mj->i", g, f)
        if is_unseen_motion(w) != want_unseen:
            continue
        if joint is None:
            norm = float(np.linalg.norm(w))
            sign = 1.0
        else:
            task = articulated_task(joint[0], joint[1], joint[2], info.centre, info.length)
            tau = float(task.projection[0] @ w)
            norm, sign = abs(tau), float(np.sign(tau))
        if norm < 1e-6:
            continue
        forces = f / norm
        if float(np.max(np.einsum("ij,ij->i", forces, -normals))) > 1.0:
            continue
        break
    else:
        return None
    if joint is None:
        return rigid_labels(info, contacts, normals, forces, mu, rng)
    jt, axis, origin = joint
    rng.uniform()  # the motion size a rigid example draws here: kept, so a seed's data set is what it was
    if jt == "revolute":
        amount = sign * float(rng.uniform(*REVOLUTE_ANGLE))
    else:
        amount = sign * float(rng.uniform(*PRISMATIC_SHIFT)) * info.scale
    out: dict[str, Any] = {"friction": mu, "forces": forces, "articulated": True}
    out["motion"] = joint_point_motion(info.points, jt, axis, origin, amount)
    out["delta_x"], out["delta_theta"] = np.zeros(3), np.zeros(3)
    out["joint_type"], out["joint_axis"], out["joint_origin"] = jt, axis, origin
    out["joint_amount"] = amount
    return _with_maps(out, info, contacts, normals, forces, rng)


def rigid_labels(
    info: ObjectInfo, contacts: np.ndarray, normals: np.ndarray, forces: np.ndarray, mu: float,
    rng: np.random.Generator,
) -> dict[str, Any]:  # fmt: skip
    """A rigid example's labels for a grasp and its forces (m, 3): the motion of their wrench (inverse of Eq. 4,
    scaled to a random size), heatmap, force map, region mask."""
    size = float(np.exp(rng.uniform(*np.log(MOTION_SCALE)))) * info.scale
    out: dict[str, Any] = {"friction": mu, "forces": forces, "articulated": False}
    dx, dth = motion_from_wrench(contact_wrench(contacts, forces, info.centre), info.mass, info.inertia)
    dx, dth = scale_motion(info.points, info.centre, dx, dth, size)
    out["motion"] = rigid_point_motion(info.points, info.centre, dx, dth)
    out["delta_x"], out["delta_theta"] = dx, dth
    out["joint_type"], out["joint_axis"], out["joint_origin"] = "", np.zeros(3), np.zeros(3)
    return _with_maps(out, info, contacts, normals, forces, rng)


def _with_maps(
    out: dict[str, Any], info: ObjectInfo, contacts: np.ndarray, normals: np.ndarray, forces: np.ndarray,
    rng: np.random.Generator,
) -> dict[str, Any]:  # fmt: skip
    heat, force_map = heat_and_force(info.points, info.normals, contacts, normals, forces, info.scale)
    out["heat"], out["force_map"] = heat, force_map
    out["mask"] = region_mask(info.points, contacts, info.scale, rng)
    return out
