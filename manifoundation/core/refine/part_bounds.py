"""Cheap bounds on a convex part's clearance, so that only a few object points are measured against all its faces.

The object-point guards (`manifoundation.core.refine.object_guards`) measure each object point near a fingertip
against every face of the convex parts of its body: ``c(x) = max_f n_f·x − d_f`` (minus the depth inside, a lower
bound on the distance outside). LEAP's fingertip hulls have up to 4 800 faces, so ≈ 200 object points cost ≈ 1 M
products a part and an iterate. Only the 8 smallest clearances below a margin enter the step's rows.

``c`` is convex and 1-Lipschitz (unit normals), so on a grid of its values (body frame, built once per hand):

- the trilinear interpolation of the 8 corners is an upper bound (x is the trilinear convex combination of the
  corners, and a convex function lies below the chord), and
- ``max_i c(corner_i) − |x − corner_i|`` is a lower bound (Lipschitz).

A point whose lower bound is above the 8th smallest upper bound cannot be among the 8 smallest: the guards then
measure exactly, on all faces, only the points that can be (the same rows as measuring every point).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit

GRID_STEP = 1.5e-3
"""m: node spacing (a finer grid prunes more points but costs nodes × faces to build once per hand)."""
BLOCK = 4
"""Nodes per block side: the build measures each block's nodes only on the faces that can be the largest there."""


def clearance(planes: np.ndarray, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """A convex part's clearance ``max_f n_f·x − d_f`` (M,) at body-frame points (M, 3) and the face attaining it
    (M,); planes (f, 4) rows ``(n, d)``."""
    result: tuple[np.ndarray, np.ndarray] = _clearance(
        np.ascontiguousarray(planes, dtype=np.float64), np.ascontiguousarray(x, dtype=np.float64)
    )
    return result


@njit(cache=True)
def _clearance(planes: np.ndarray, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """`clearance` as a loop over the faces per point (compiled; no (M, f) array): the first face attaining the
    maximum, as argmax gives."""
    m = x.shape[0]
    value, face = np.empty(m), np.zeros(m, dtype=np.int64)
    for i in range(m):
        x0, x1, x2 = x[i, 0], x[i, 1], x[i, 2]
        best = -np.inf
        for f in range(planes.shape[0]):
            e = x0 * planes[f, 0] + x1 * planes[f, 1] + x2 * planes[f, 2] - planes[f, 3]
            if e > best:
                best, face[i] = e, f
        value[i] = best
    return value, face


@dataclass(frozen=True)
class PartGrid:
    """The clearance of one convex part sampled on a grid: ``origin`` (3,), ``step`` (m), ``values`` (nx, ny, nz).

    The grid covers the part's bounds grown by ``margin`` + one step, so every point within its bounds grown by
    ``margin`` has all 8 corners of its cell on the grid.
    """

    origin: np.ndarray
    step: float
    values: np.ndarray

    @classmethod
    def build(cls, planes: np.ndarray, bounds: np.ndarray, margin: float, step: float = GRID_STEP) -> PartGrid:
        """Sample the clearance of the part ``planes`` (f, 4) with ``bounds`` (2, 3) on a grid (see class doc)."""
        extent = bounds[1] - bounds[0] + 2 * (margin + step)
        origin = bounds[0] - margin - step
        shape = np.ceil(extent / step).astype(np.int64) + 2
        blocks = -(-shape // BLOCK)
        values = np.empty(blocks * BLOCK)
        offsets = np.stack(np.meshgrid(*[np.arange(BLOCK)] * 3, indexing="ij"), axis=-1).reshape(-1, 3)
        corner = np.stack(np.meshgrid(*[np.arange(b) for b in blocks], indexing="ij"), axis=-1).reshape(-1, 3)
        centre = origin + step * (corner * BLOCK + 0.5 * (BLOCK - 1))
        radius = 0.5 * np.sqrt(3.0) * step * (BLOCK - 1)
        at_centre = centre @ planes[:, :3].T - planes[:, 3][None]  # (blocks, f)
        for b in range(len(corner)):
            # a face more than 2r below the best at the block's centre is below the best everywhere in it (the
            # faces are 1-Lipschitz, and the best is at least max − r there): the node values are exact
            faces = planes[at_centre[b] >= at_centre[b].max() - 2 * radius - 1e-12]
            ijk = corner[b] * BLOCK + offsets
            values[ijk[:, 0], ijk[:, 1], ijk[:, 2]] = clearance(faces, origin + step * ijk)[0]
        return cls(origin, step, values[: shape[0], : shape[1], : shape[2]].copy())

    def bounds(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Lower and upper bounds (M,), (M,) of the clearance at body-frame points (M, 3) within the grid."""
        result: tuple[np.ndarray, np.ndarray] = _grid_bounds(
            np.ascontiguousarray(x, dtype=np.float64), self.origin, self.step, self.values
        )
        return result


@njit(cache=True)
def _grid_bounds(x: np.ndarray, origin: np.ndarray, step: float, values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """`PartGrid.bounds` as one loop per point (compiled): the cell's 8 corner values, their trilinear
    interpolation (upper) and max_i v_i − |x − corner_i| (lower)."""
    m = x.shape[0]
    lower, upper = np.empty(m), np.empty(m)
    top = (values.shape[0] - 2, values.shape[1] - 2, values.shape[2] - 2)
    cell = np.empty(3, dtype=np.int64)
    frac = np.empty(3)
    for i in range(m):
        for a in range(3):
            rel = (x[i, a] - origin[a]) / step
            c = min(max(int(np.floor(rel)), 0), top[a])
            cell[a], frac[a] = c, rel - c
        up, low = 0.0, -np.inf
        for ci in range(2):
            for cj in range(2):
                for ck in range(2):
                    v = values[cell[0] + ci, cell[1] + cj, cell[2] + ck]
                    w = ((frac[0] if ci else 1.0 - frac[0]) * (frac[1] if cj else 1.0 - frac[1])
                         * (frac[2] if ck else 1.0 - frac[2]))  # fmt: skip
                    up += w * v
                    d0, d1, d2 = (frac[0] - ci) * step, (frac[1] - cj) * step, (frac[2] - ck) * step
                    low = max(low, v - np.sqrt(d0 * d0 + d1 * d1 + d2 * d2))
        lower[i], upper[i] = low, up
    return lower, upper


def part_grids(parts: list[tuple[np.ndarray, np.ndarray]], margin: float) -> list[PartGrid]:
    """One `PartGrid` per convex part (planes (f, 4), bounds (2, 3)) of a fingertip body."""
    return [PartGrid.build(planes, bounds, margin) for planes, bounds in parts]


def part_boxes(parts: list[tuple[np.ndarray, np.ndarray]], margin: float) -> np.ndarray:
    """(2, P, 3): the bounds (2, 3) of each convex part (planes, bounds) grown by ``margin``, stacked (one
    comparison tests a point against every part's box)."""
    if not parts:
        return np.zeros((2, 0, 3))
    return np.stack([np.stack([bounds[0] - margin for _, bounds in parts]),
                     np.stack([bounds[1] + margin for _, bounds in parts])])  # fmt: skip
