"""Per-point motion from an unordered target cloud: non-rigid registration, then optimal transport.

1. Coherent point drift (Myronenko & Song, "Point Set Registration: Coherent Point Drift", TPAMI 2010, the
   non-rigid variant with its default β = 2, λ = 2 in clouds scaled to unit size): the start cloud is the
   centroids of a Gaussian mixture that an EM moves onto the target by a smooth displacement field
   v(z) = Σ_m G(z, y_m) w_m, G Gaussian of width β. Clouds above ``CPD_MAX`` points fit the field on a
   farthest-point subsample; the field then moves every start point.
2. Optimal transport between the moved start cloud and the target: with uniform masses and squared-distance cost
   the optimal plan is a permutation (Birkhoff–von Neumann), so the exact solver is the linear assignment problem
   (`scipy.optimize.linear_sum_assignment`). The motion of start point i is target[π(i)] − start_i. With fewer
   target than start points the unmatched start points take the motion of their nearest matched neighbour;
   clouds above ``MAX_EXACT`` points are matched on a farthest-point subsample and interpolated the same way.

``method="ot"`` skips step 1. Errors of both on simulated pairs: docs/deformables.md.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import linear_sum_assignment
from scipy.spatial import cKDTree

MAX_EXACT = 1500
CPD_MAX = 400
CPD_BETA, CPD_LAMBDA, CPD_ITERATIONS = 2.0, 2.0, 60


def _farthest(points: np.ndarray, k: int) -> np.ndarray:
    pick = [0]
    dist = np.linalg.norm(points - points[0], axis=1)
    for _ in range(k - 1):
        pick.append(int(np.argmax(dist)))
        dist = np.minimum(dist, np.linalg.norm(points - points[pick[-1]], axis=1))
    return np.array(pick)


def _gauss(a: np.ndarray, b: np.ndarray, beta: float) -> np.ndarray:
    kernel: np.ndarray = np.exp(-np.square(a[:, None] - b[None]).sum(-1) / (2.0 * beta**2))
    return kernel


def coherent_point_drift(source: np.ndarray, target: np.ndarray, beta: float = CPD_BETA,
                         lam: float = CPD_LAMBDA, iterations: int = CPD_ITERATIONS) -> np.ndarray:  # fmt: skip
    """``source`` (M, 3) moved onto ``target`` (N, 3) by non-rigid CPD (see the module doc); returns (M, 3)."""
    centre, scale = source.mean(axis=0), max(float(np.ptp(source, axis=0).max()), 1e-12)
    y_all, x = (source - centre) / scale, (target - centre) / scale
    sub = np.arange(len(y_all)) if len(y_all) <= CPD_MAX else _farthest(y_all, CPD_MAX)
    y = y_all[sub]
    m, n, dim = len(y), len(x), 3
    g = _gauss(y, y, beta)
    w = np.zeros((m, dim))
    moved = y.copy()
    sigma2 = float(np.square(x[None] - y[:, None]).sum()) / (dim * m * n)
    for _ in range(iterations):
        d2 = np.square(x[None] - moved[:, None]).sum(-1)
        p = np.exp(-(d2 - d2.min(axis=0, keepdims=True)) / (2.0 * sigma2))  # shifted per column: no underflow
        p /= p.sum(axis=0, keepdims=True)
        p1, pt1, px = p.sum(axis=1), p.sum(axis=0), p @ x
        w = np.linalg.solve(p1[:, None] * g + lam * sigma2 * np.eye(m), px - p1[:, None] * y)
        moved = y + g @ w
        resid = pt1 @ np.square(x).sum(1) - 2.0 * np.sum(px * moved) + p1 @ np.square(moved).sum(1)
        sigma2 = max(float(resid) / (p1.sum() * dim), 1e-10)
    registered: np.ndarray = (y_all + _gauss(y_all, y, beta) @ w) * scale + centre
    return registered


def transport_motion(start: np.ndarray, target: np.ndarray, method: str = "cpd") -> np.ndarray:
    """(N, 3) per-point motion taking ``start`` (N, 3) onto the unordered ``target`` (M, 3) cloud.

    Args:
        start: the object's cloud. target: the target cloud, any order and count.
        method: "cpd" (registration, then transport; default) or "ot" (transport only).

    Raises:
        ValueError: non-finite or malformed clouds, or an unknown method.
    """
    a, b = np.asarray(start, dtype=np.float64), np.asarray(target, dtype=np.float64)
    if a.ndim != 2 or b.ndim != 2 or a.shape[1] != 3 or b.shape[1] != 3 or len(a) == 0 or len(b) == 0:
        raise ValueError(f"targets: expected (M, 3) and (N, 3) clouds, got {b.shape} and {a.shape}")
    if not (np.all(np.isfinite(a)) and np.all(np.isfinite(b))):
        raise ValueError("targets: NaN or inf")
    if method not in ("cpd", "ot"):
        raise ValueError(f"method: {method!r} is not 'cpd' or 'ot'")
    moved = coherent_point_drift(a, b) if method == "cpd" else a
    src = np.arange(len(a)) if len(a) <= MAX_EXACT else _farthest(a, MAX_EXACT)
    dst = np.arange(len(b)) if len(b) <= MAX_EXACT else _farthest(b, MAX_EXACT)
    cost = np.square(moved[src][:, None, :] - b[dst][None, :, :]).sum(-1)
    rows, cols = linear_sum_assignment(cost)
    matched = src[rows]
    motion = np.full(a.shape, np.nan)
    motion[matched] = b[dst[cols]] - a[matched]
    missing = np.flatnonzero(np.isnan(motion[:, 0]))
    if len(missing):
        _, near = cKDTree(a[matched]).query(a[missing])
        motion[missing] = motion[matched[near]]
    return motion
