"""Cheap bounds on a convex part's clearance, so that only a few object points are measured against all its faces.

The object-point guards (`models.refine.object_guards`) measure each object point near a fingertip
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

GRID_STEP = 1.5e-3
"""m: node spacing (a finer grid prunes more points but costs nodes × faces to build once per hand)."""
BLOCK = 4
"""Nodes per block side: the build measures each block's nodes only on the faces that can be the largest there."""
_CORNERS = np.array([[i, j, k] for i in (0, 1) for j in (0, 1) for k in (0, 1)], dtype=np.int64)  # (8, 3)


def clearance(planes: np.ndarray, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """A convex part's clearance ``max_f n_f·x − d_f`` (M,) at body-frame points (M, 3) and the face attaining it
    (M,); planes (f, 4) rows ``(n, d)``."""
    excess = x @ planes[:, :3].T - planes[:, 3][None]  # (M, f) > 0 outside a face
    face = np.argmax(excess, axis=1)
    return excess[np.arange(len(x)), face], face


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
        rel = (x - self.origin) / self.step
        shape = np.asarray(self.values.shape)
        cell = np.clip(np.floor(rel).astype(np.int64), 0, shape - 2)  # (M, 3)
        frac = rel - cell  # (M, 3) in [0, 1] inside the grid
        corner = cell[:, None, :] + _CORNERS[None]  # (M, 8, 3)
        v = self.values[corner[..., 0], corner[..., 1], corner[..., 2]]  # (M, 8)
        weight = np.prod(np.where(_CORNERS[None] == 1, frac[:, None, :], 1.0 - frac[:, None, :]), axis=2)
        upper = np.einsum("mc,mc->m", weight, v)
        gap = np.linalg.norm((frac[:, None, :] - _CORNERS[None]) * self.step, axis=2)  # |x − corner|
        lower = np.max(v - gap, axis=1)
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
