"""Collision spheres and surface samples generated from a hand's collision meshes (deterministic).

Sphere procedure, per body mesh (in the body frame):

1. Take the mesh vertices plus ``SURFACE_SAMPLES`` surface samples (seed 0).
2. PCA of those points; the first principal axis is the link's long axis (sign fixed: largest component > 0).
3. Cut the points into ``n = clip(ceil(L / (SLAB_RATIO * w_min)), 1, MAX_PER_LINK)`` equal slabs along that axis
   (L the length along it, w_min the smaller cross-section extent).
4. One sphere per non-empty slab: centre = centre of the slab points' bounding box (in the PCA frame), radius =
   largest distance from it to a slab point + ``MARGIN``.

Each sphere contains every sampled point of its slab by construction, so the surface is covered up to the sampling
gap (< ``MARGIN`` for the meshes we ship: tests check fresh samples with a stated tolerance).
"""

from __future__ import annotations

from typing import cast

import numpy as np
import trimesh

SURFACE_SAMPLES = 3000
SLAB_RATIO = 0.75
MAX_PER_LINK = 6
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
    ext = hi - lo
    w_min = max(min(ext[1], ext[2]), 1e-4)
    n = int(np.clip(np.ceil(ext[0] / (SLAB_RATIO * w_min)), 1, MAX_PER_LINK))
    edges = np.linspace(lo[0], hi[0], n + 1)
    slab = np.clip(np.searchsorted(edges, local[:, 0], side="right") - 1, 0, n - 1)
    centres, radii = [], []
    for s in range(n):
        p = local[slab == s]
        if len(p) == 0:
            continue
        c = 0.5 * (p.min(0) + p.max(0))
        radii.append(float(np.linalg.norm(p - c, axis=1).max()) + MARGIN)
        centres.append(c @ vt + mean)
    return np.asarray(centres), np.asarray(radii)


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
