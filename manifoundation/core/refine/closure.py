"""Ferrari–Canny ε (L1 / "sum of normal forces ≤ 1" grasp wrench space) with linearised friction cones.

The cones are linearised (an ``edges``-sided pyramid) for the metric only; the optimisation uses exact cones.
Wrenches are the scaled ones of `manifoundation.core.refine.wrench` (torque over ρ), so ε is dimensionless and
comparable across object sizes. ε > 0 ⇔ the origin is strictly inside the convex hull of the primitive wrenches ⇔ force
closure. Point contacts with friction: two contacts can never reach ε > 0 (no torque about the line through
them); ``torsional`` adds soft-finger primitives ``±γ f_n`` about the normal (torque γ in metres), the model we
use for the pads of parallel-jaw grippers.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import ConvexHull, QhullError

from manifoundation.core.refine.grasp import grasp_maps, tangents


def primitive_wrenches(
    points: np.ndarray,
    normals: np.ndarray,
    mu: float | np.ndarray,
    centre: np.ndarray,
    length: float,
    edges: int = 8,
    torsional: float = 0.0,
) -> np.ndarray:
    """(m·edges [+ 2m], 6) scaled wrenches of unit-normal-force pyramid edges (and torsional primitives)."""
    t1, t2 = tangents(normals)
    n = normals / np.linalg.norm(normals, axis=1, keepdims=True)
    angles = 2 * np.pi * np.arange(edges) / edges
    mu_c = np.asarray(mu, dtype=np.float64).reshape(-1, 1, 1)  # one μ, or one per contact
    dirs = (
        -n[:, None, :]
        + mu_c * np.cos(angles)[None, :, None] * t1[:, None, :]
        + mu_c * np.sin(angles)[None, :, None] * t2[:, None, :]
    )  # (m, edges, 3)
    g = grasp_maps(points, centre, length)  # (m, 6, 3)
    prims: np.ndarray = np.einsum("mij,mej->mei", g, dirs).reshape(-1, 6)
    if torsional > 0:
        normal_w = np.einsum("mij,mj->mi", g, -n)
        spin = np.concatenate([np.zeros_like(n), torsional / length * n], axis=1)
        prims = np.concatenate([prims, normal_w + spin, normal_w - spin])
    return prims


def ferrari_canny(
    points: np.ndarray,
    normals: np.ndarray,
    mu: float | np.ndarray,
    centre: np.ndarray,
    length: float,
    edges: int = 8,
    torsional: float = 0.0,
) -> float:
    """ε = radius of the largest origin-centred ball inside the grasp wrench space (0 if not force closure).

    Args:
        points: (m, 3) contact points. normals: (m, 3) outward normals. mu: friction coefficient.
        centre, length: wrench reference point and torque scale ρ.
        edges: sides of the friction pyramid. torsional: soft-finger torque coefficient γ (m), 0 = point contact.

    Returns:
        ε ≥ 0.
    """
    prims = primitive_wrenches(points, normals, mu, centre, length, edges, torsional)
    if np.linalg.matrix_rank(prims, tol=1e-9) < 6:
        return 0.0
    try:
        hull = ConvexHull(prims)
    except QhullError:
        return 0.0
    # equations: a·x + b ≤ 0 inside, ‖a‖ = 1; distance from the origin to a facet = −b
    return max(0.0, float(np.min(-hull.equations[:, -1])))
