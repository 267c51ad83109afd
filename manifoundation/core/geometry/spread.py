"""Random, well-spread contact points on a cloud: the ``random_contacts`` method's and the evaluation's start."""

from __future__ import annotations

import numpy as np


def spread_contacts(points: np.ndarray, count: int, rng: np.random.Generator) -> np.ndarray:
    """Indices of ``count`` farthest-point-spread points in a random half-space-ish subset of the cloud."""
    direction = rng.normal(size=3)
    side = points @ direction
    pool = np.flatnonzero(side >= np.quantile(side, rng.uniform(0.2, 0.5)))
    chosen = [int(rng.choice(pool))]
    dist = np.linalg.norm(points[pool] - points[chosen[0]], axis=1)
    for _ in range(count - 1):
        nxt = int(pool[np.argmax(dist)])
        chosen.append(nxt)
        dist = np.minimum(dist, np.linalg.norm(points[pool] - points[nxt], axis=1))
    return np.asarray(chosen)
