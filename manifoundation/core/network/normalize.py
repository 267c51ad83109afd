"""Input normalisation, invertible, so the network's outputs come back in the request's frame and units.

For one object with points x (N, 3) in the request's frame:

- centre ``c`` = centre of the axis-aligned bounding box, scale ``s`` = its longest side (metres);
- positions: ``x' = (x - c) / s`` — the object fits the unit box [-0.5, 0.5]^3;
- normals: unchanged (translation and uniform scaling do not change directions);
- motions (displacements): ``m' = m / s`` — same scale as positions, no translation;
- the force/motion map the network predicts is in the same normalised units as the motions, so it goes back
  as ``f = f' · s`` (forces and motions are scaled consistently; there is no rotation, so directions are kept).

The hand point cloud is *not* normalised per object (its encoding is cached per hand): it is divided by the
constant ``NetworkConfig.hand_scale_m``; the object's scale ``s`` is given to the network as an input so the
hand/object size ratio is not lost.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

MIN_SCALE = 1e-6  # a cloud smaller than this (metres) is degenerate


@dataclass(frozen=True)
class Normalizer:
    """The affine map of one object: ``x' = (x - centre) / scale``.

    Attributes:
        centre: (3,) bounding-box centre in the request's frame.
        scale: longest bounding-box side, > 0.
    """

    centre: np.ndarray
    scale: float

    @classmethod
    def fit(cls, points: np.ndarray) -> Normalizer:
        """The normaliser of ``points`` (N, 3).

        Raises:
            ValueError: empty, non-finite, or degenerate (all points within ``MIN_SCALE``) cloud.
        """
        pts = np.asarray(points, dtype=np.float64)
        if pts.ndim != 2 or pts.shape[1] != 3 or pts.shape[0] == 0:
            raise ValueError(f"points must be (N, 3) with N ≥ 1, got {pts.shape}")
        if not np.isfinite(pts).all():
            raise ValueError("points contain NaN or inf")
        lo, hi = pts.min(axis=0), pts.max(axis=0)
        scale = float((hi - lo).max())
        if scale < MIN_SCALE:
            raise ValueError(f"point cloud is degenerate (extent {scale:g} < {MIN_SCALE:g})")
        return cls(centre=(lo + hi) / 2.0, scale=scale)

    def points(self, x: np.ndarray) -> np.ndarray:
        """Positions to the normalised frame."""
        result: np.ndarray = (np.asarray(x, dtype=np.float64) - self.centre) / self.scale
        return result

    def vectors(self, v: np.ndarray) -> np.ndarray:
        """Motions (or forces) to normalised units."""
        return np.asarray(v, dtype=np.float64) / self.scale

    def unpoints(self, x: np.ndarray) -> np.ndarray:
        """Inverse of :meth:`points`."""
        result: np.ndarray = np.asarray(x, dtype=np.float64) * self.scale + self.centre
        return result

    def unvectors(self, v: np.ndarray) -> np.ndarray:
        """Inverse of :meth:`vectors`: network force/motion maps back to the request's units."""
        return np.asarray(v, dtype=np.float64) * self.scale
