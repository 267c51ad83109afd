"""`ObjectGeometry`: an oriented point cloud with a KD-tree signed distance, a watertight mesh and mass properties.

Signed distance (paper §III-B): for a query x, the nearest cloud point p̄ with outward normal n̄ gives
Φ(x) = n̄·(x − p̄), ∂Φ/∂x = n̄ (negative inside). The region-masked distance Φ^R (paper footnote) uses only the
allowed points: |Φ^R(x)| = |x − p̄^R| with gradient (x − p̄^R)/|x − p̄^R|; we keep the side sign of n̄^R·(x − p̄^R)
so that points behind the allowed region read negative.

Normals, when missing, are estimated by PCA over the ``NORMAL_NEIGHBOURS`` nearest points and oriented outward:
first away from the centroid, then by a few rounds of neighbour majority votes (consistent on smooth shapes).
Mesh, when missing (or given but not watertight): the convex hull of the points (and the mesh's vertices) —
conservative for non-convex objects: penetration checks against it over-report depth in concavities.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import trimesh
from scipy.spatial import cKDTree

from manifoundation.core.errors import InvalidPointCloud

DEFAULT_DENSITY = 500.0
"""kg/m³: a mid value for household objects (wood ~500-700, hollow plastic parts less, water 1000)."""
DEFAULT_FRICTION = 0.5
"""Coulomb μ when a caller gives none (the wire contract's default is the same value; a test keeps them equal)."""
NORMAL_NEIGHBOURS = 16


@dataclass
class MassProperties:
    """Mass (kg), centre of mass (3,) and inertia (3, 3) about the centre of mass, in the object frame."""

    mass: float
    com: np.ndarray
    inertia: np.ndarray


@dataclass
class ObjectGeometry:
    """Points (N, 3), outward unit normals (N, 3), a watertight ``mesh`` and a KD-tree over the points."""

    points: np.ndarray
    normals: np.ndarray
    mesh: trimesh.Trimesh
    tree: cKDTree = field(repr=False)
    _region: tuple[int, np.ndarray, cKDTree] | None = field(default=None, repr=False, compare=False)

    @classmethod
    def from_points(
        cls, points: np.ndarray, normals: np.ndarray | None = None, mesh: trimesh.Trimesh | None = None
    ) -> ObjectGeometry:
        """Build from an (N, 3) cloud, optional (N, 3) normals (normalised here) and optional watertight mesh."""
        pts = np.asarray(points, dtype=np.float64)
        if pts.ndim != 2 or pts.shape[1] != 3 or len(pts) < 4:
            raise InvalidPointCloud(f"points must be (N, 3) with N >= 4, got {pts.shape}")
        if not np.all(np.isfinite(pts)):
            raise InvalidPointCloud("points contain NaN or inf")
        tree = cKDTree(pts)
        if normals is None:
            n = estimate_normals(pts, tree, mesh)
        else:
            n = np.asarray(normals, dtype=np.float64)
            if n.shape != pts.shape or not np.all(np.isfinite(n)):
                raise InvalidPointCloud(f"normals must be finite with shape {pts.shape}, got {n.shape}")
            norm = np.linalg.norm(n, axis=1, keepdims=True)
            if np.any(norm < 1e-12):
                raise InvalidPointCloud("normals contain zero vectors")
            n = n / norm
        if mesh is None:
            mesh = trimesh.convex.convex_hull(pts)
        elif not mesh.is_watertight:  # exact checks need an inside: fall back to the hull of mesh + cloud
            mesh = trimesh.convex.convex_hull(np.vstack([np.asarray(mesh.vertices), pts]))
        return cls(pts, n, mesh, tree)

    @property
    def volume(self) -> float:
        return float(abs(self.mesh.volume))

    def signed_distance(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Φ (M,), ∂Φ/∂x (M, 3) and the nearest point index (M,) for queries (M, 3)."""
        x = np.asarray(x, dtype=np.float64).reshape(-1, 3)
        _, idx = self.tree.query(x)
        n = self.normals[idx]
        phi = np.einsum("ij,ij->i", n, x - self.points[idx])
        return phi, n, idx

    def masked_signed_distance(self, x: np.ndarray, mask: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Φ^R (M,), its gradient (M, 3) and nearest index (into the full cloud) w.r.t. the allowed points only."""
        mask = np.asarray(mask, dtype=bool).reshape(-1)
        if mask.shape != (len(self.points),) or not mask.any():
            raise InvalidPointCloud(f"mask must be ({len(self.points)},) bool with at least one True")
        x = np.asarray(x, dtype=np.float64).reshape(-1, 3)
        key = hash(mask.tobytes())
        if self._region is None or self._region[0] != key:  # one tree per mask, reused across iterations
            allowed = np.nonzero(mask)[0]
            self._region = (key, allowed, cKDTree(self.points[allowed]))
        _, allowed, region_tree = self._region
        _, k = region_tree.query(x)
        idx = allowed[k]
        d = x - self.points[idx]
        dist = np.linalg.norm(d, axis=1)
        side = np.where(np.einsum("ij,ij->i", d, self.normals[idx]) < 0, -1.0, 1.0)
        safe = dist > 1e-12
        grad = np.where(safe[:, None], d / np.where(safe, dist, 1.0)[:, None], self.normals[idx]) * side[:, None]
        return side * dist, grad, idx

    def mass_properties(self, density: float = DEFAULT_DENSITY) -> MassProperties:
        """Mass, centre of mass and inertia (about the COM) of the watertight mesh at uniform ``density``."""
        if not np.isfinite(density) or density <= 0:
            raise ValueError(f"density must be positive and finite, got {density}")
        mp = trimesh.triangles.mass_properties(self.mesh.triangles, density=density)
        mass = float(abs(mp["mass"]))
        inertia = np.asarray(mp["inertia"], dtype=np.float64)
        if mp["volume"] < 0:  # inward-wound mesh
            inertia = -inertia
        return MassProperties(mass, np.asarray(mp["center_mass"], dtype=np.float64), inertia)


def estimate_normals(points: np.ndarray, tree: cKDTree, mesh: trimesh.Trimesh | None = None) -> np.ndarray:
    """Outward unit normals by local PCA, oriented by the mesh (when given) or outward from the centroid with
    neighbour majority votes."""
    k = min(NORMAL_NEIGHBOURS, len(points))
    _, nb = tree.query(points, k=k)
    nbp = points[nb] - points[nb].mean(axis=1, keepdims=True)
    cov = np.einsum("nki,nkj->nij", nbp, nbp)
    _, vecs = np.linalg.eigh(cov)
    n = vecs[:, :, 0]
    if mesh is not None:
        _, _, tri = trimesh.proximity.closest_point(mesh, points)
        ref = np.asarray(mesh.face_normals)[tri]
    else:
        ref = points - points.mean(0)
    n = np.where((np.einsum("ij,ij->i", n, ref) < 0)[:, None], -n, n)
    if mesh is None:
        for _ in range(3):  # flip points that disagree with most of their neighbours
            votes = np.einsum("nkj,nj->n", n[nb[:, 1:]], n)
            n = np.where((votes < 0)[:, None], -n, n)
    unit: np.ndarray = n / np.linalg.norm(n, axis=1, keepdims=True)
    return unit
