"""Grasp maps G_i (scaled wrench of a contact force) and friction-cone rows."""

from __future__ import annotations

import numpy as np


def skew(v: np.ndarray) -> np.ndarray:
    """(..., 3) → (..., 3, 3) cross-product matrices, ``skew(a) @ b = a × b``."""
    v = np.asarray(v)
    out = np.zeros((*v.shape[:-1], 3, 3))
    out[..., 0, 1], out[..., 0, 2] = -v[..., 2], v[..., 1]
    out[..., 1, 0], out[..., 1, 2] = v[..., 2], -v[..., 0]
    out[..., 2, 0], out[..., 2, 1] = -v[..., 1], v[..., 0]
    return out


def grasp_maps(points: np.ndarray, centre: np.ndarray, length: float) -> np.ndarray:
    """G_i (m, 6, 3): a world-frame force f at p_i gives the scaled wrench ``[f; (p_i − c) × f / ρ]``."""
    m = len(points)
    g = np.zeros((m, 6, 3))
    g[:, :3, :] = np.eye(3)
    g[:, 3:, :] = skew(points - centre) / length
    return g


def tangents(normals: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit tangents (m, 3) each, forming right-handed frames with the normals."""
    n = normals / np.linalg.norm(normals, axis=-1, keepdims=True)
    helper = np.where(np.abs(n[:, :1]) < 0.9, np.array([[1.0, 0.0, 0.0]]), np.array([[0.0, 1.0, 0.0]]))
    t1 = np.cross(n, helper)
    t1 /= np.linalg.norm(t1, axis=-1, keepdims=True)
    return t1, np.cross(n, t1)


def cone_rows(normals: np.ndarray, mu: float | np.ndarray) -> np.ndarray:
    """C_i (m, 3, 3) with ``C_i f ∈ SOC`` ⇔ f in the friction cone at a contact with *outward* normal n_i.

    Rows: ``μ (−n_i)``, ``t1``, ``t2``: the force pushes into the object with tangential part ≤ μ times the
    normal part. ``mu``: one coefficient, or one per contact (m,).
    """
    t1, t2 = tangents(normals)
    n = normals / np.linalg.norm(normals, axis=-1, keepdims=True)
    return np.stack([-np.asarray(mu, dtype=np.float64).reshape(-1, 1) * n, t1, t2], axis=1)
