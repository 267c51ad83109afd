"""Rigid motion from point correspondences (Kabsch / weighted Procrustes).

Model: targets ≈ R @ points + t, a rotation R **about the world origin** followed by a translation t. To express
the same motion as a rotation about a centre c (e.g. the object's centre of mass): Δθ = rotation_vector(R),
Δx = R c + t − c.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation


@dataclass
class RigidFit:
    """rotation (3, 3), translation (3,) and the weighted RMS residual (m)."""

    rotation: np.ndarray
    translation: np.ndarray
    rms: float


def fit_rigid_motion(points: np.ndarray, targets: np.ndarray, weights: np.ndarray | None = None) -> RigidFit:
    """The proper rotation R and translation t minimising Σ w_i ‖R p_i + t − q_i‖² (Kabsch, with reflection fix).

    Args:
        points: (N, 3) source points p.
        targets: (N, 3) target points q (e.g. p + per-point motion).
        weights: (N,) non-negative, not all zero (default uniform).
    """
    p = np.asarray(points, dtype=np.float64)
    q = np.asarray(targets, dtype=np.float64)
    if p.shape != q.shape or p.ndim != 2 or p.shape[1] != 3 or len(p) == 0:
        raise ValueError(f"points and targets must both be (N, 3), got {p.shape} and {q.shape}")
    w = np.ones(len(p)) if weights is None else np.asarray(weights, dtype=np.float64).reshape(-1)
    if w.shape != (len(p),) or np.any(w < 0) or w.sum() <= 0 or not np.all(np.isfinite(w)):
        raise ValueError("weights must be (N,), finite, non-negative and not all zero")
    w = w / w.sum()
    pc, qc = w @ p, w @ q
    H = (p - pc).T @ ((q - qc) * w[:, None])
    U, _, Vt = np.linalg.svd(H)
    d = np.sign(np.linalg.det(Vt.T @ U.T)) or 1.0
    R = Vt.T @ np.diag([1.0, 1.0, d]) @ U.T
    t = qc - R @ pc
    res = p @ R.T + t - q
    return RigidFit(R, t, float(np.sqrt(w @ np.einsum("ij,ij->i", res, res))))


def rotation_vector(rotation: np.ndarray) -> np.ndarray:
    """Axis-angle vector (3,) (angle = norm, radians) of a (3, 3) rotation matrix."""
    return np.asarray(Rotation.from_matrix(np.asarray(rotation, dtype=np.float64)).as_rotvec())
