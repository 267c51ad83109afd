"""Labels of one example: target motion from a wrench (inverse of Eq. 4), heatmap, force map, region mask.

Kernel (documented, used for training and evaluation alike). With s the object's longest bounding-box side
(the network's normalisation scale), contacts c_i with outward normals n_i and forces f_i, point j gets

    k_ij = exp(-|x_j - c_i|² / (2 (σ s)²)) · max(0, n_j·n_i)        σ = HEAT_SIGMA = 0.05
    heat_j = max_i k_ij            force_j = Σ_i k_ij f_i

so the heatmap is 1 at a contact, 0.5 at ≈ 1.18 σ s, and the force map reads the contact force at the peak
(the value NMS picks). The normal factor keeps the kernel from bleeding through thin walls.

Region masks (paper appendix): with probability 1/2 all ones; otherwise the points within r = U(0.1, 0.25)·s
of any contact (the contacts and their neighbourhood).
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

HEAT_SIGMA = 0.05
MASK_RADIUS = (0.1, 0.25)
MOTION_SCALE = (0.02, 0.2)  # largest per-point displacement as a fraction of s, log-uniform


def kernel(
    points: np.ndarray, normals: np.ndarray, contacts: np.ndarray, contact_normals: np.ndarray, scale: float
) -> np.ndarray:
    """k (N, H) of the module docstring."""
    d2 = np.square(points[:, None, :] - contacts[None, :, :]).sum(-1)
    gate = np.clip(normals @ contact_normals.T, 0.0, None)
    k: np.ndarray = np.exp(-d2 / (2.0 * (HEAT_SIGMA * scale) ** 2)) * gate
    return k


def heat_and_force(
    points: np.ndarray,
    normals: np.ndarray,
    contacts: np.ndarray,
    contact_normals: np.ndarray,
    forces: np.ndarray,
    scale: float,
) -> tuple[np.ndarray, np.ndarray]:
    """Ground-truth heatmap (N,) in [0, 1] and force map (N, 3) (same units as ``forces``)."""
    k = kernel(points, normals, contacts, contact_normals, scale)
    return k.max(axis=1), k @ forces


def region_mask(points: np.ndarray, contacts: np.ndarray, scale: float, rng: np.random.Generator) -> np.ndarray:
    """(N,) bool region mask: all ones half the time, else the contacts' neighbourhood."""
    if rng.random() < 0.5:
        return np.ones(len(points), dtype=bool)
    r = rng.uniform(*MASK_RADIUS) * scale
    d = np.linalg.norm(points[:, None, :] - contacts[None, :, :], axis=-1).min(axis=1)
    mask: np.ndarray = d <= r
    mask[np.argmin(np.linalg.norm(points[:, None, :] - contacts[None, :, :], axis=-1), axis=0)] = True
    return mask


def contact_wrench(contacts: np.ndarray, forces: np.ndarray, centre: np.ndarray) -> np.ndarray:
    """Unscaled wrench [Σ f_i; Σ (c_i − centre) × f_i] (6,)."""
    return np.concatenate([forces.sum(0), np.cross(contacts - centre, forces).sum(0)])


def motion_from_wrench(
    wrench: np.ndarray, mass: float, inertia: np.ndarray, dt: float = 1.0
) -> tuple[np.ndarray, np.ndarray]:
    """Inverse of Eq. 4 (physical form ``ŵ = 2/Δt² [M Δx; I Δθ]``, see manifoundation.core.refine.wrench): (Δx, Δθ)."""
    w = np.asarray(wrench, dtype=np.float64)
    return w[:3] * dt**2 / (2.0 * mass), np.linalg.solve(inertia, w[3:]) * dt**2 / 2.0


def rigid_point_motion(
    points: np.ndarray, centre: np.ndarray, delta_x: np.ndarray, delta_theta: np.ndarray
) -> np.ndarray:
    """Per-point displacement (N, 3) of the motion: rotate by Δθ about ``centre``, then translate by Δx."""
    rot = Rotation.from_rotvec(delta_theta).as_matrix()
    motion: np.ndarray = (points - centre) @ rot.T + centre + delta_x - points
    return motion


def scale_motion(
    points: np.ndarray, centre: np.ndarray, delta_x: np.ndarray, delta_theta: np.ndarray, target: float
) -> tuple[np.ndarray, np.ndarray]:
    """Scale (Δx, Δθ) jointly (direction kept) so the largest linearised point displacement is ``target``."""
    lin = delta_x + np.cross(delta_theta, points - centre)
    peak = float(np.linalg.norm(lin, axis=1).max())
    if peak < 1e-15:
        raise ValueError("zero motion")
    f = target / peak
    return delta_x * f, delta_theta * f


def joint_point_motion(
    points: np.ndarray, joint_type: str, axis: np.ndarray, origin: np.ndarray, amount: float
) -> np.ndarray:
    """Per-point displacement of a joint motion: rotation by ``amount`` rad about (axis, origin), or a slide."""
    a = np.asarray(axis, dtype=np.float64) / np.linalg.norm(axis)
    if joint_type == "prismatic":
        return np.broadcast_to(a * amount, points.shape).copy()
    rot = Rotation.from_rotvec(a * amount).as_matrix()
    motion: np.ndarray = (points - origin) @ rot.T + origin - points
    return motion
