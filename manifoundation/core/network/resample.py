"""Resampling an object of any size N to the model's point count M, and mapping outputs back to the N points.

- N > M: exact farthest point sampling keeps M points; each original point then takes the inverse-distance
  weighted mean of the outputs at its 3 nearest kept points (a kept point takes its own output).
- N ≤ M: every point is kept; the cloud is repeated ⌊M/N⌋ times and the remaining M mod N slots are filled
  with an FPS subset, so the duplicated points are spread evenly. Each original point takes the output of its
  first copy (copies of a point are identical inputs and get identical outputs).
- N = M: the identity.

Both choices are permutation-equivariant (FPS starts at the point farthest from the mean), so permuting the
request's points permutes the outputs the same way.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from manifoundation.core.network.point_ops import farthest_point_sample_np


@dataclass(frozen=True)
class Resampling:
    """Indices into the original cloud and the map back.

    Attributes:
        indices: (M,) original index of each model point.
        back_idx: (N, k) model-point indices each original point reads from.
        back_w: (N, k) their weights (rows sum to 1).
    """

    indices: np.ndarray
    back_idx: np.ndarray
    back_w: np.ndarray

    def map_back(self, values: np.ndarray) -> np.ndarray:
        """Model-point outputs (K, M, C) → original-point outputs (K, N, C)."""
        if self.back_idx.shape[1] == 1:
            return values[:, self.back_idx[:, 0], :]
        gathered = values[:, self.back_idx, :]  # (K, N, k, C)
        result: np.ndarray = (gathered * self.back_w[None, :, :, None].astype(values.dtype)).sum(axis=2)
        return result


def resample(points: np.ndarray, m: int) -> Resampling:
    """Choose M model points from ``points`` (N, 3) as described in the module docstring."""
    n = points.shape[0]
    if n == m:
        idx = np.arange(n)
        return Resampling(idx, idx[:, None], np.ones((n, 1)))
    if n > m:
        keep = farthest_point_sample_np(points, m)
        dist, nn = cKDTree(points[keep]).query(points, k=3)
        w = 1.0 / (np.square(dist) + 1e-12)
        return Resampling(keep, nn.astype(np.int64), w / w.sum(axis=1, keepdims=True))
    reps, rest = divmod(m, n)
    parts = [np.tile(np.arange(n), reps)]
    if rest:
        parts.append(farthest_point_sample_np(points, rest))
    return Resampling(np.concatenate(parts), np.arange(n)[:, None], np.ones((n, 1)))
