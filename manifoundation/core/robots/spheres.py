"""Collision spheres and surface samples generated from a hand's collision meshes (deterministic).

Sphere procedure, per body mesh (in the body frame):

1. Take the mesh vertices plus ``SURFACE_SAMPLES`` surface samples (seed 0).
2. PCA of those points: the principal frame and extents e1 ≥ e2 ≥ e3.
3. A sphere budget ``K = clip(round(A / AREA_PER_SPHERE), 1, MAX_PER_LINK)``, A the area of the PCA box;
   grids of cubic cells of size s = e1 · SHRINK^k (k = 0, 1, ... while s > ``MIN_CELL``), each principal axis
   cut into ``ceil(e_i / s)`` cells; keep the finest grid whose occupied cells number at most K (the scan
   stops past 4 K).
4. One sphere per non-empty cell: centre = centre of the cell points' bounding box (in the PCA frame), radius =
   largest distance from it to a cell point + ``MARGIN``.

Each sphere contains every sampled point of its cell by construction, so the surface is covered up to the sampling
gap (< ``MARGIN`` for the meshes we ship: tests check fresh samples with a stated tolerance).
"""

from __future__ import annotations

from typing import cast

import numpy as np
import trimesh

SURFACE_SAMPLES = 3000
AREA_PER_SPHERE = 1e-3
MAX_PER_LINK = 24
MIN_CELL = 4e-3
SHRINK = 0.9
MARGIN = 1e-3


def fit_spheres(mesh: trimesh.Trimesh) -> tuple[np.ndarray, np.ndarray]:
    """Spheres covering ``mesh``: centres (k, 3) and radii (k,) in the mesh frame (see module doc)."""
    if len(mesh.faces) == 0:
        return np.zeros((0, 3)), np.zeros(0)
    samples, _ = trimesh.sample.sample_surface(mesh, SURFACE_SAMPLES, seed=0)
    pts = np.vstack([np.asarray(mesh.vertices), samples])
    mean = pts.mean(0)
    _, _, vt = np.linalg.svd(pts - mean, full_matrices=False)
    for i in range(3):  # deterministic signs
        if vt[i][np.argmax(np.abs(vt[i]))] < 0:
            vt[i] = -vt[i]
    local = (pts - mean) @ vt.T
    lo, hi = local.min(0), local.max(0)
    ext = np.maximum(hi - lo, 1e-6)
    box_area = 2.0 * float(ext[0] * ext[1] + ext[0] * ext[2] + ext[1] * ext[2])
    budget = int(np.clip(round(box_area / AREA_PER_SPHERE), 1, MAX_PER_LINK))
    best = np.zeros(len(local), dtype=np.int64)
    size = float(ext[0])
    while size > MIN_CELL:  # the finest grid whose occupied cells fit the budget
        n = [max(1, int(np.ceil(e / size - 1e-9))) for e in ext]
        cell = (_bins(local[:, 0], lo[0], hi[0], n[0]) * n[1] + _bins(local[:, 1], lo[1], hi[1], n[1])) * n[2]
        cell = cell + _bins(local[:, 2], lo[2], hi[2], n[2])
        occupied = len(np.unique(cell))
        if occupied <= budget:
            best = cell
        elif occupied > 4 * budget:  # finer grids only occupy more cells
            break
        size *= SHRINK
    cell = best
    used = np.unique(cell)
    centres, radii = [], []
    for s in used:
        p = local[cell == s]
        c = 0.5 * (p.min(0) + p.max(0))
        radii.append(float(np.linalg.norm(p - c, axis=1).max()) + MARGIN)
        centres.append(c @ vt + mean)
    return np.asarray(centres), np.asarray(radii)


def _bins(x: np.ndarray, lo: float, hi: float, n: int) -> np.ndarray:
    edges = np.linspace(lo, hi, n + 1)
    return np.clip(np.searchsorted(edges, x, side="right") - 1, 0, n - 1)


def sample_surface(meshes: list[trimesh.Trimesh], count: int, oversample: int = 8) -> tuple[np.ndarray, np.ndarray]:
    """``count`` well-spread surface points with outward face normals on the union of ``meshes``.

    Samples ``oversample * count`` points by area (seed 0), then keeps ``count`` by farthest-point sampling.
    """
    mesh = cast(trimesh.Trimesh, trimesh.util.concatenate([m for m in meshes if len(m.faces)]))
    pts, face = trimesh.sample.sample_surface(mesh, oversample * count, seed=0)
    normals = np.asarray(mesh.face_normals)[face]
    keep = farthest_points(pts, count)
    return np.asarray(pts[keep], dtype=np.float64), np.asarray(normals[keep], dtype=np.float64)


def farthest_points(points: np.ndarray, count: int) -> np.ndarray:
    """Indices of ``count`` points by exact farthest-point sampling from index 0 (deterministic; fpsample)."""
    import fpsample

    if count >= len(points):
        return np.arange(len(points))
    return np.asarray(fpsample.fps_sampling(np.ascontiguousarray(points, dtype=np.float64), count, start_idx=0))
