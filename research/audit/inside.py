"""Exact point-in-mesh tests by ray parity, fast: rays binned on a 2-D grid of triangles, three votes.

A point is inside a closed (watertight) mesh when a ray from it crosses the surface an odd number of times.
Rays go along +z of a frame turned by a fixed, generic rotation (so that axis-aligned inputs never graze an edge
or a vertex of the mesh); triangles are binned by their projected bounding boxes on a grid of cells, so each ray
meets only the triangles of its cell. Three rotations vote (a ray that still grazes an edge can miscount once).
It answers what ``trimesh.Trimesh.contains`` answers, orders of magnitude faster (no per-ray R-tree queries).
"""

from __future__ import annotations

import numpy as np
import trimesh
from numpy.typing import ArrayLike


def _rotation(seed: int) -> np.ndarray:
    q = np.random.default_rng(seed).normal(size=4)
    w, x, y, z = q / np.linalg.norm(q)
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


ROTATIONS = tuple(_rotation(seed) for seed in (11, 23, 37))


class _Grid:
    """Triangles (rotated) binned by their xy bounding boxes."""

    def __init__(self, triangles: np.ndarray, rotation: np.ndarray) -> None:
        self.rotation = rotation
        tri = triangles @ rotation.T  # (F, 3, 3)
        self.tri = tri
        lo, hi = tri[:, :, :2].min(axis=(0, 1)), tri[:, :, :2].max(axis=(0, 1))
        self.n = int(np.clip(np.sqrt(len(tri) / 2), 4, 256))
        self.lo, self.cell = lo, np.maximum((hi - lo) / self.n, 1e-12)
        tmin = self._cell(tri[:, :, :2].min(axis=1))
        tmax = self._cell(tri[:, :, :2].max(axis=1))
        span = tmax - tmin + 1  # (F, 2) cells covered per axis
        count = span[:, 0] * span[:, 1]
        tri_id = np.repeat(np.arange(len(tri)), count)
        local = np.arange(int(count.sum())) - np.repeat(np.cumsum(count) - count, count)
        ix = tmin[tri_id, 0] + local // span[tri_id, 1]
        iy = tmin[tri_id, 1] + local % span[tri_id, 1]
        cell_id = ix * self.n + iy
        order = np.argsort(cell_id, kind="stable")
        self.tri_of = tri_id[order]
        self.start = np.searchsorted(cell_id[order], np.arange(self.n * self.n + 1))
        self.zmax = float(tri[:, :, 2].max())

    def _cell(self, xy: np.ndarray) -> np.ndarray:
        cell: np.ndarray = np.clip(((xy - self.lo) / self.cell).astype(np.int64), 0, self.n - 1)
        return cell

    def crossings(self, points: np.ndarray) -> np.ndarray:
        """(N,) number of surface crossings of the +z ray from each (unrotated) point."""
        p = points @ self.rotation.T
        out = np.zeros(len(p), dtype=np.int64)
        xy = p[:, :2]
        inside_box = np.all((xy >= self.lo) & (xy <= self.lo + self.n * self.cell), axis=1) & (p[:, 2] <= self.zmax)
        idx = np.flatnonzero(inside_box)
        if not len(idx):
            return out
        c = self._cell(xy[idx])
        cid = c[:, 0] * self.n + c[:, 1]
        first, num = self.start[cid], self.start[cid + 1] - self.start[cid]
        pair_pt = np.repeat(idx, num)
        offset = np.arange(int(num.sum())) - np.repeat(np.cumsum(num) - num, num)
        pair_tri = self.tri_of[np.repeat(first, num) + offset]
        t = self.tri[pair_tri]  # (K, 3, 3)
        q = p[pair_pt]  # (K, 3)
        a, b, cc = t[:, 0], t[:, 1], t[:, 2]
        e0 = (b[:, 0] - a[:, 0]) * (q[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (q[:, 0] - a[:, 0])
        e1 = (cc[:, 0] - b[:, 0]) * (q[:, 1] - b[:, 1]) - (cc[:, 1] - b[:, 1]) * (q[:, 0] - b[:, 0])
        e2 = (a[:, 0] - cc[:, 0]) * (q[:, 1] - cc[:, 1]) - (a[:, 1] - cc[:, 1]) * (q[:, 0] - cc[:, 0])
        area = e0 + e1 + e2
        hit = ((e0 >= 0) & (e1 >= 0) & (e2 >= 0)) | ((e0 <= 0) & (e1 <= 0) & (e2 <= 0))
        hit &= np.abs(area) > 1e-300
        z = (e1 * a[:, 2] + e2 * b[:, 2] + e0 * cc[:, 2]) / np.where(hit, area, 1.0)
        hit &= z > q[:, 2]
        out += np.bincount(pair_pt, weights=hit, minlength=len(p)).astype(np.int64)
        return out


class InsideTest:
    """Point-in-mesh tests against one closed mesh (build once, query many times)."""

    def __init__(self, mesh: trimesh.Trimesh) -> None:
        """Bin the mesh's triangles.

        Args:
            mesh: a watertight mesh (for other meshes the answer is the parity of crossings, not "inside").
        """
        triangles = np.asarray(mesh.triangles, dtype=np.float64)
        self.grids = [_Grid(triangles, r) for r in ROTATIONS]
        self.bounds = np.asarray(mesh.bounds, dtype=np.float64)

    def contains(self, points: ArrayLike) -> np.ndarray:
        """(N,) whether each point (N, 3) is inside the mesh (majority of three ray directions)."""
        p = np.asarray(points, dtype=np.float64).reshape(-1, 3)
        result = np.zeros(len(p), dtype=bool)
        near = np.flatnonzero(np.all((p >= self.bounds[0]) & (p <= self.bounds[1]), axis=1))
        if len(near):
            votes = sum((g.crossings(p[near]) % 2) for g in self.grids)
            result[near] = np.asarray(votes) >= 2
        return result
