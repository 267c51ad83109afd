"""Point-cloud distance fields: a continuous variant of the paper's Φ(x) = n̄·(x − p̄), and of Φ^R(x) = |x − p̄^R|.

A KD-tree over the oriented points (≈50× faster than mesh queries). The paper's Φ = n̄·(x − p̄) jumps where the
nearest sample switches between faces (outside a box's edge it measures the distance to the wrong face's plane
and jumped by 3 cm in our runs, which stalls the trust region). We treat each sample as a disc of radius h (0.75 ×
the mean sample spacing) with normal n̄: with a = n̄·(x − p̄) and b the tangential offset, Φ = a while b ≤ h (the
paper's value) and Φ = sign(a)·√(a² + (b − h)²), the distance to the disc, beyond it. Near the surface this is the
paper's Φ; away from it the Euclidean distance to the samples, without jumps larger than the sample spacing.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree


class PointCloudField:
    """Signed distance to an oriented point cloud, and unsigned distance to a masked region of it.

    Args:
        points: (N, 3). normals: (N, 3) outward unit normals. mask: (N,) bool region allowed for fingertips.
    """

    def __init__(self, points: np.ndarray, normals: np.ndarray, mask: np.ndarray | None = None) -> None:
        self.points = np.asarray(points, dtype=np.float64)
        n = np.asarray(normals, dtype=np.float64)
        self.normals = n / np.linalg.norm(n, axis=1, keepdims=True)
        self._tree = cKDTree(self.points)
        self.mask = None if mask is None else np.asarray(mask, dtype=bool)
        if self.mask is not None:
            if self.mask.shape != (len(self.points),) or not self.mask.any():
                raise ValueError("mask must be (N,) bool with at least one allowed point")
            self._region = np.flatnonzero(self.mask)
            self._region_tree = cKDTree(self.points[self._region])
        spacing = self._tree.query(self.points[: min(len(self.points), 512)], k=2)[0][:, 1]
        self.disc_radius = 0.75 * float(np.mean(spacing))

    def signed_distance(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Φ (M,), ∇Φ (M, 3) (= n̄ near the surface), nearest sample p̄ (M, 3).

        Beyond a disc the side (sign) comes from the weighted mean of n_j·(x − p_j) over the 8 nearest samples,
        not from the nearest one alone: next to an edge the nearest sample's normal is almost perpendicular to
        x − p̄ and its sign flips under millimetre moves (a 16 mm jump of Φ in our runs).
        """
        x = np.asarray(x, dtype=np.float64)
        k = min(8, len(self.points))
        dist, idx = self._tree.query(x, k=k)
        near, nrm = self.points[idx[:, 0]], self.normals[idx[:, 0]]
        d = x - near
        a = np.einsum("ij,ij->i", d, nrm)
        tang = d - a[:, None] * nrm
        b = np.linalg.norm(tang, axis=1)
        excess = np.maximum(b - self.disc_radius, 0.0)
        w = np.exp(-((dist - dist[:, :1]) ** 2) / (2.0 * self.disc_radius) ** 2)
        side = np.einsum("mk,mka,mka->m", w, self.normals[idx], x[:, None, :] - self.points[idx])
        sign = np.where(excess > 0, np.where(side < 0, -1.0, 1.0), np.where(a < 0, -1.0, 1.0))
        radial = np.sqrt(a**2 + excess**2)
        phi = np.where(excess > 0, sign * radial, a)
        t_hat = tang / np.maximum(b, 1e-12)[:, None]
        far = sign[:, None] * (a[:, None] * nrm + excess[:, None] * t_hat) / np.maximum(radial, 1e-12)[:, None]
        grad = np.where((excess > 0)[:, None], far, nrm)
        return phi, grad, near

    def surface_normal(self, x: np.ndarray) -> np.ndarray:
        """Smoothed outward normal (M, 3) at x: Gaussian-weighted mean of the 16 nearest samples' normals (σ = 2 ×
        the disc radius). Grasp maps and friction cones use it; it varies smoothly on curved surfaces, so the
        step can model how sliding a contact turns its friction cone (`normal_jacobian`)."""
        x = np.asarray(x, dtype=np.float64)
        k = min(16, len(self.points))
        dist, idx = self._tree.query(x, k=k)
        sigma = 2.0 * self.disc_radius
        w = np.exp(-((dist - dist[:, :1]) ** 2) / sigma**2)
        n = np.einsum("mk,mka->ma", w, self.normals[idx])
        return n / np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-12)

    def normal_jacobian(self, x: np.ndarray, h: float = 1e-3) -> np.ndarray:
        """∂n/∂x (M, 3, 3) of `surface_normal` by central differences with step ``h`` (m)."""
        x = np.asarray(x, dtype=np.float64)
        steps = np.concatenate([np.eye(3), -np.eye(3)]) * h
        probe = (x[:, None, :] + steps[None]).reshape(-1, 3)
        n = self.surface_normal(probe).reshape(len(x), 6, 3)
        return np.transpose((n[:, :3] - n[:, 3:]) / (2 * h), (0, 2, 1))

    def region_distance(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Φ^R (M,): distance to the allowed region's surface, and its gradient (M, 3) (unit; the outward normal
        on the region). The refinement's tip objective with a mask.

        The region is the union of the allowed samples' discs (radius ``disc_radius``, as in `signed_distance`):
        Φ^R is the distance to the nearest of the 8 nearest allowed discs. The distance to the nearest allowed
        *point* (the verification's test, `region_point_distance`) never reaches 0 between samples and its
        gradient jumps where the nearest sample changes: masked LEAP refinements stalled 5-10 mm "off" on
        it with the trust region collapsed. Without a mask this is |Φ| with gradient sign(Φ) n̄.
        """
        x = np.asarray(x, dtype=np.float64)
        if self.mask is None:
            phi, grad, _ = self.signed_distance(x)
            return np.abs(phi), grad * np.where(phi < 0, -1.0, 1.0)[:, None]
        k = min(8, len(self._region))
        _, idx = self._region_tree.query(x, k=k)
        j = self._region[np.asarray(idx).reshape(len(x), k)]  # (M, k)
        p, n = self.points[j], self.normals[j]
        d = x[:, None, :] - p
        a = np.einsum("mka,mka->mk", d, n)
        tang = d - a[..., None] * n
        b = np.linalg.norm(tang, axis=2)
        excess = np.maximum(b - self.disc_radius, 0.0)
        value = np.sqrt(a**2 + excess**2)
        best = np.argmin(value, axis=1)
        rows = np.arange(len(x))
        a, excess, value = a[rows, best], excess[rows, best], value[rows, best]
        n, t_hat = n[rows, best], tang[rows, best] / np.maximum(b[rows, best], 1e-12)[:, None]
        grad = (a[:, None] * n + excess[:, None] * t_hat) / np.maximum(value, 1e-12)[:, None]
        grad = np.where((value > 1e-9)[:, None], grad, n)
        return value, grad

    def region_point_distance(self, x: np.ndarray) -> np.ndarray:
        """(M,) distance to the nearest allowed sample (without a mask: |Φ|) — the verification's region test."""
        x = np.asarray(x, dtype=np.float64)
        if self.mask is None:
            return np.abs(self.signed_distance(x)[0])
        return np.asarray(self._region_tree.query(x)[0], dtype=np.float64)

    def ball_indices(self, x: np.ndarray, radius: float) -> list[list[int]]:
        """For each x, the indices of the cloud points within ``radius``."""
        return list(self._tree.query_ball_point(np.asarray(x, dtype=np.float64), radius))

    def nearest_index(self, x: np.ndarray) -> np.ndarray:
        """Index of the nearest cloud point for each x."""
        return np.asarray(self._tree.query(np.asarray(x, dtype=np.float64))[1])
