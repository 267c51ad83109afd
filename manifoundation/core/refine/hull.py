"""The convex hull of an object's points, grown by a margin: a point outside it is outside the object.

`manifoundation.core.refine.field.PointCloudField` asks it about the off-surface points whose side the discs leave
unclear before it pays for their winding number. A 2 048-point cloud's hull has 1 000-4 000 facets; a point outside any
facet's plane (by more than the margin) is outside, so a few facets with spread normals settle most points — 95 %
of those the refinement asks about lie outside one of 32 — and only the rest are tested on every facet. The
answer is the full test's.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from manifoundation.core.refine.field_kernels import within_facets

PROBE_FACETS = 32
"""Facets with spread normals tested first."""


@dataclass(frozen=True)
class GrownHull:
    """Hull facets ``equations`` (F, 4) (n·x + d ≤ 0 inside, Qhull's), the ``probe`` rows among them, the margin
    ``grow`` (m) and the points' bounding box grown by it (``lo``, ``hi``)."""

    equations: np.ndarray
    probe: np.ndarray
    grow: float
    lo: np.ndarray
    hi: np.ndarray

    @classmethod
    def of(cls, hull_points: np.ndarray, box_points: np.ndarray, grow: float) -> GrownHull | None:
        """The hull of ``hull_points`` (K, 3) grown by ``grow``, inside the box of ``box_points`` (N, 3) grown as
        much; None for flat or degenerate points (no hull to rule anything out)."""
        from scipy.spatial import ConvexHull, QhullError

        try:
            equations = np.asarray(ConvexHull(hull_points).equations)
        except (QhullError, ValueError):
            return None
        probe = equations[spread_facets(equations[:, :3], PROBE_FACETS)]
        return cls(equations, probe, grow, box_points.min(0) - grow, box_points.max(0) + grow)

    def contains(self, x: np.ndarray) -> np.ndarray:
        """(M,) bool: points ``x`` (M, 3) within the grown box and within every grown facet."""
        result: np.ndarray = within_facets(np.ascontiguousarray(x, dtype=np.float64), self.lo, self.hi,
                                           self.probe, self.equations, self.grow)  # fmt: skip
        return result


def spread_facets(normals: np.ndarray, count: int) -> np.ndarray:
    """Indices of up to ``count`` facets whose unit normals (F, 3) are spread over the sphere (greedy farthest
    point: each next one is the facet least aligned with those chosen)."""
    chosen = [0]
    closest = normals @ normals[0]
    for _ in range(min(count, len(normals)) - 1):
        nxt = int(np.argmin(closest))
        chosen.append(nxt)
        closest = np.maximum(closest, normals @ normals[nxt])
    return np.asarray(chosen)
