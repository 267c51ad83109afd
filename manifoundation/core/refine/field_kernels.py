"""Compiled loops of the point field (`manifoundation.core.refine.field`): the discs' distances, the winding number, the
hull.

`PointCloudField.signed_distance` is asked ≈ 50 times a request for ≈ 180 points each; written as numpy it was ≈ 40
array operations of 1-10 µs on (M, 8) arrays — call overhead, not arithmetic. The same formulas as one loop per
point (numba, compiled once per machine and cached beside this file) do the work of a call in a few µs. Each
kernel is the numpy formula it replaces, term for term; `tests/core/refine/test_field_kernels.py` checks them
against plain numpy on random inputs.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit


@njit(cache=True, fastmath=False)
def disc_distances(
    x: np.ndarray, idx: np.ndarray, points: np.ndarray, normals: np.ndarray, radius: float,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:  # fmt: skip
    """The distance to the nearest of each point's candidate discs, and the discs' vote on its side.

    Args:
        x: (M, 3) query points. idx: (M, k) indices of their k nearest samples. points, normals: (N, 3) the
            samples and their unit normals. radius: the discs' radius h.

    Returns:
        nearest (M,): min_j √(a_j² + max(b_j − h, 0)²), a_j = n_j·(x − p_j), b_j the tangential offset.
        best (M,): the sample index of that disc.
        side (M,): Σ_j w_j cos_j |cos_j|, w_j = exp(−((d_j − d_min)/h)²), cos_j = a_j / d_j.
        weight (M,): Σ_j w_j.
        grad (M, 3): ∇ of the unsigned distance to the nearest disc, for the outward side: sign(a) n inside
            the disc's rim, (a n + e t̂) / d beyond it.
    """
    m, k = idx.shape
    nearest = np.empty(m)
    best = np.empty(m, dtype=np.int64)
    side = np.empty(m)
    weight = np.empty(m)
    grad = np.empty((m, 3))
    a = np.empty(k)
    value = np.empty(k)
    for i in range(m):
        x0, x1, x2 = x[i, 0], x[i, 1], x[i, 2]
        jb = 0
        for j in range(k):
            s = idx[i, j]
            d0, d1, d2 = x0 - points[s, 0], x1 - points[s, 1], x2 - points[s, 2]
            aj = d0 * normals[s, 0] + d1 * normals[s, 1] + d2 * normals[s, 2]
            t0, t1, t2 = d0 - aj * normals[s, 0], d1 - aj * normals[s, 1], d2 - aj * normals[s, 2]
            b = math.sqrt(t0 * t0 + t1 * t1 + t2 * t2)
            e = max(b - radius, 0.0)
            a[j] = aj
            value[j] = math.sqrt(aj * aj + e * e)
            if value[j] < value[jb]:
                jb = j
        v = value[jb]
        vote = 0.0
        total = 0.0
        for j in range(k):
            w = math.exp(-(((value[j] - v) / radius) ** 2))
            c = a[j] / max(value[j], 1e-12)
            vote += w * c * abs(c)
            total += w
        s = idx[i, jb]
        nearest[i], best[i], side[i], weight[i] = v, s, vote, total
        d0, d1, d2 = x0 - points[s, 0], x1 - points[s, 1], x2 - points[s, 2]
        ab = a[jb]
        t0, t1, t2 = d0 - ab * normals[s, 0], d1 - ab * normals[s, 1], d2 - ab * normals[s, 2]
        b = math.sqrt(t0 * t0 + t1 * t1 + t2 * t2)
        e = max(b - radius, 0.0)
        if e <= 0.0:
            sg = 1.0 if ab + 1e-300 > 0 else (-1.0 if ab + 1e-300 < 0 else 0.0)
            grad[i, 0], grad[i, 1], grad[i, 2] = sg * normals[s, 0], sg * normals[s, 1], sg * normals[s, 2]
        else:
            bb = max(b, 1e-12)
            vv = max(v, 1e-12)
            grad[i, 0] = (ab * normals[s, 0] + e * (t0 / bb)) / vv
            grad[i, 1] = (ab * normals[s, 1] + e * (t1 / bb)) / vv
            grad[i, 2] = (ab * normals[s, 2] + e * (t2 / bb)) / vv
    return nearest, best, side, weight, grad


@njit(cache=True)
def winding_sum(
    x: np.ndarray, centre: np.ndarray, radius: np.ndarray, moment: np.ndarray, start: np.ndarray,
    count: np.ndarray, points: np.ndarray, weighted: np.ndarray, far: float, floor: float,
) -> np.ndarray:  # fmt: skip
    """Σ over the samples of (p_j − x)·a_j n_j / |p_j − x|³ for each query point (M,): a cell (C cells: centre,
    radius, moment Σ a_j n_j) farther than ``far`` × its radius contributes its dipole, a nearer one its samples
    (``points``/``weighted`` (N, 3) sorted by cell from ``start``, ``count`` of them; |p − x| at least
    ``floor``). The generalised winding number is this over 4π."""
    m = x.shape[0]
    out = np.zeros(m)
    for i in range(m):
        x0, x1, x2 = x[i, 0], x[i, 1], x[i, 2]
        total = 0.0
        for c in range(centre.shape[0]):
            d0, d1, d2 = centre[c, 0] - x0, centre[c, 1] - x1, centre[c, 2] - x2
            dist = math.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
            if dist > far * radius[c] + 1e-9:
                total += (d0 * moment[c, 0] + d1 * moment[c, 1] + d2 * moment[c, 2]) / max(dist, 1e-12) ** 3
            else:
                for j in range(start[c], start[c] + count[c]):
                    e0, e1, e2 = points[j, 0] - x0, points[j, 1] - x1, points[j, 2] - x2
                    r = max(math.sqrt(e0 * e0 + e1 * e1 + e2 * e2), floor)
                    total += (e0 * weighted[j, 0] + e1 * weighted[j, 1] + e2 * weighted[j, 2]) / r**3
        out[i] = total
    return out


@njit(cache=True)
def within_facets(
    x: np.ndarray, lo: np.ndarray, hi: np.ndarray, probe: np.ndarray, equations: np.ndarray, grow: float,
) -> np.ndarray:  # fmt: skip
    """(M,) bool: each point lies in the box [lo, hi] and within ``grow`` of every facet's half-space (``probe``
    (P, 4) facets tested first: most outside points leave on one of them; ``equations`` (F, 4) n·x + d ≤ 0)."""
    m = x.shape[0]
    out = np.zeros(m, dtype=np.bool_)
    for i in range(m):
        x0, x1, x2 = x[i, 0], x[i, 1], x[i, 2]
        if x0 < lo[0] or x1 < lo[1] or x2 < lo[2] or x0 > hi[0] or x1 > hi[1] or x2 > hi[2]:
            continue
        inside = True
        for f in range(probe.shape[0]):
            if probe[f, 0] * x0 + probe[f, 1] * x1 + probe[f, 2] * x2 + probe[f, 3] > grow:
                inside = False
                break
        if inside:
            for f in range(equations.shape[0]):
                if equations[f, 0] * x0 + equations[f, 1] * x1 + equations[f, 2] * x2 + equations[f, 3] > grow:
                    inside = False
                    break
        out[i] = inside
    return out
