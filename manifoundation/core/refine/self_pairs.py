"""The self-collision sphere pairs that are near at a pose: every pair's gap, in one compiled loop.

LEAP has 8 513 sphere pairs; the step only uses those with a gap below its ``pair_margin`` and the merit those that
overlap. A body-level bound (each body's spheres in one ball) used to leave ≈ 40 % of them unmeasured, but kept
≈ 5 900 of which ≈ 800 were within reach, at ≈ 0.3 ms a linearisation of numpy; measuring every pair exactly as a
loop costs ≈ 0.03 ms and keeps only those within ``PAIR_REACH``. The pairs kept are in the hand's order, so the rows
the step builds from them are the same rows in the same order.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

PAIR_REACH = 0.02
"""m: sphere pairs with a gap below this are kept (≥ the step's ``pair_margin``, 0.01 m; overlaps are below 0)."""


def near_pairs(
    centres: np.ndarray, radii: np.ndarray, pairs: np.ndarray, reach: float = PAIR_REACH,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:  # fmt: skip
    """The sphere pairs (P, 2) (indices into centres (S, 3), radii (S,)) whose gap |c_i − c_j| − r_i − r_j is
    below ``reach``: their rows in ``pairs`` (K,) ascending, centre distances (K,) and unit directions c_i − c_j
    (K, 3) (zero-length: divided by 1e-12)."""
    result: tuple[np.ndarray, np.ndarray, np.ndarray] = _near_pairs(
        np.ascontiguousarray(centres, dtype=np.float64), np.ascontiguousarray(radii, dtype=np.float64),
        np.ascontiguousarray(pairs, dtype=np.int64).reshape(-1, 2), float(reach),
    )  # fmt: skip
    return result


@njit(cache=True)
def _near_pairs(
    centres: np.ndarray, radii: np.ndarray, pairs: np.ndarray, reach: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    n = pairs.shape[0]
    rows = np.empty(n, dtype=np.int64)
    dist = np.empty(n)
    direction = np.empty((n, 3))
    k = 0
    for p in range(n):
        i, j = pairs[p, 0], pairs[p, 1]
        d0, d1, d2 = centres[i, 0] - centres[j, 0], centres[i, 1] - centres[j, 1], centres[i, 2] - centres[j, 2]
        d = math.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
        if d - (radii[i] + radii[j]) < reach:
            rows[k], dist[k] = p, d
            s = max(d, 1e-12)
            direction[k, 0], direction[k, 1], direction[k, 2] = d0 / s, d1 / s, d2 / s
            k += 1
    return rows[:k].copy(), dist[:k].copy(), direction[:k].copy()
