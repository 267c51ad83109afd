"""`DeformableBody`: a simulation mesh (vertices + elements) and the point cloud the network sees on it."""

from __future__ import annotations

import hashlib
from dataclasses import dataclass, field

import numpy as np

from manifoundation.core.deformable.materials import ROPE_RADIUS, check_material

ELEMENT_SIZE = {"rope": 4, "cloth": 3, "plasticine": 4}  # vertices per element: triangle or tetrahedron


@dataclass(frozen=True)
class DeformableBody:
    """A deformable object at rest on the table (z = 0 is the table, +z up), metres.

    Attributes:
        material: cloth (triangles), rope or plasticine (tetrahedra).
        kind: the shape's name (square, tshirt, rope, sphere, ...).
        vertices: (V, 3) rest positions of the simulation mesh.
        elements: (E, k) vertex indices, k = 3 (cloth) or 4 (rope, plasticine).
        surface: (N,) indices of the vertices that form the object's point cloud (all of them for cloth and
            rope, the boundary vertices for plasticine).
        normals: (N, 3) unit normals of the cloud (up for cloth, outward for rope and plasticine).
        properties: contract properties (friction, density, stretch, bending, youngs_modulus, poisson_ratio,
            yield_stress; those of the material).
        seed: the seed the shape was drawn with.
    """

    material: str
    kind: str
    vertices: np.ndarray
    elements: np.ndarray
    surface: np.ndarray
    normals: np.ndarray
    properties: dict[str, float] = field(default_factory=dict)
    seed: int = 0

    def __post_init__(self) -> None:
        check_material(self.material)
        v, e = np.asarray(self.vertices), np.asarray(self.elements)
        if v.ndim != 2 or v.shape[1] != 3 or not np.all(np.isfinite(v)):
            raise ValueError(f"vertices: expected finite (V, 3), got {v.shape}")
        k = ELEMENT_SIZE[self.material]
        if e.ndim != 2 or e.shape[1] != k or e.min() < 0 or e.max() >= len(v):
            raise ValueError(f"elements: expected (E, {k}) indices into {len(v)} vertices, got {e.shape}")
        if np.shape(self.normals) != (len(self.surface), 3):
            raise ValueError("normals: one per surface vertex")

    @property
    def points(self) -> np.ndarray:
        """(N, 3) the object's point cloud (surface vertices)."""
        points: np.ndarray = np.asarray(self.vertices)[self.surface]
        return points

    @property
    def id(self) -> str:
        """Stable id, e.g. ``tshirt-3f2a9c1e``, from the kind, the mesh and the properties."""
        h = hashlib.sha1(np.ascontiguousarray(self.vertices, dtype=np.float64).tobytes())
        h.update(repr(sorted(self.properties.items())).encode())
        return f"{self.kind}-{h.hexdigest()[:8]}"

    @property
    def size(self) -> float:
        """Longest bounding-box side of the cloud, m."""
        return float(np.ptp(self.points, axis=0).max())

    def measure(self) -> float:
        """Area (cloth, m²), length (rope, m: volume over the cross-section) or volume (plasticine, m³)."""
        v, e = np.asarray(self.vertices, dtype=np.float64), np.asarray(self.elements)
        if self.material == "cloth":
            return float(0.5 * np.linalg.norm(np.cross(v[e[:, 1]] - v[e[:, 0]], v[e[:, 2]] - v[e[:, 0]]), axis=1).sum())
        a, b, c, d = (v[e[:, i]] for i in range(4))
        volume = float(np.abs(np.einsum("ij,ij->i", b - a, np.cross(c - a, d - a))).sum() / 6.0)
        return volume / (2 * ROPE_RADIUS) ** 2 if self.material == "rope" else volume

    def with_properties(self, properties: dict[str, float]) -> DeformableBody:
        """The same shape with other properties."""
        return DeformableBody(self.material, self.kind, self.vertices, self.elements, self.surface, self.normals,
                              dict(properties), self.seed)  # fmt: skip
