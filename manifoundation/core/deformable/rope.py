"""Ropes: a smooth random curve lying on the table, as a thin elastic rod of tetrahedra (MuJoCo 3D flex).

The centre line's heading is θ(s) = θ₀ + Σ_k a_k sin(k π s + φ_k), k = 1..3, a_k ~ U(−``CURL``, ``CURL``)/k.
The rod has a square cross-section of side 2·``ROPE_RADIUS`` (2 × 2 vertices per station, stations every
``STATION_SPACING``), each segment between stations a lattice cube split into Kuhn's six tetrahedra; its bending
stiffness is then the solid's own (≈ E·I with I the cross-section's second moment), so Young's modulus and
Poisson's ratio enter as they are. Every vertex is on the surface: the cloud is all of them, normals pointing away
from the centre line. (A 1D flex with bending elasticity was tried first: under MuJoCo 4.0's discrete integrator
it blew up whenever a lifted rope fell back to the table; docs/deformables.md.)
"""

from __future__ import annotations

import numpy as np

from manifoundation.core.deformable.body import DeformableBody
from manifoundation.core.deformable.lattice import CORNERS, KUHN
from manifoundation.core.deformable.materials import ROPE_RADIUS, sample_properties

ROPE_LENGTH = (0.3, 0.9)  # m
CURL = 1.2  # rad: largest heading swing of the first mode
STATION_SPACING = 1.5 * 2 * ROPE_RADIUS  # m
ROPE_KINDS = ("rope",)


def centre_line(length: float, rng: np.random.Generator, spacing: float = STATION_SPACING) -> np.ndarray:
    """(S, 2) points every ``spacing`` along a smooth random planar curve of ``length``, centred at the origin."""
    stations = max(2, round(length / spacing) + 1)
    s = np.linspace(0.0, 1.0, stations)
    theta = np.full_like(s, rng.uniform(0, 2 * np.pi))
    for k in range(1, 4):
        theta += rng.uniform(-CURL, CURL) / k * np.sin(k * np.pi * s + rng.uniform(0, 2 * np.pi))
    step = length / (stations - 1)
    xy = np.vstack([[0.0, 0.0], np.cumsum(step * np.column_stack([np.cos(theta[:-1]), np.sin(theta[:-1])]), axis=0)])
    centred: np.ndarray = xy - xy.mean(axis=0)
    return centred


def rod(line: np.ndarray, radius: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A square rod along a planar centre line: vertices (4S, 3), tetrahedra (6(S−1), 4), outward normals (4S, 3).

    Vertex 4i + 2b + a sits at station i, side a (across the line), layer b (0 on the table, 1 on top).
    """
    tangent = np.gradient(line, axis=0)
    tangent /= np.linalg.norm(tangent, axis=1, keepdims=True)
    across = np.column_stack([-tangent[:, 1], tangent[:, 0]])
    verts, normals = [], []
    for i in range(len(line)):
        for b in (0, 1):
            for a in (0, 1):
                u, w = (2 * a - 1), (2 * b - 1)
                verts.append([*(line[i] + u * radius * across[i]), radius + w * radius + 1e-3])
                n = np.array([u * across[i][0], u * across[i][1], w])
                normals.append(n / np.linalg.norm(n))
    tets = []
    for i in range(len(line) - 1):
        corner = [4 * (i + x) + 2 * z + y for x, y, z in CORNERS]  # lattice x along the line, y across, z up
        tets.extend([[corner[k] for k in tet] for tet in KUHN])
    return np.array(verts), np.array(tets, dtype=np.int64), np.array(normals)


def make_rope(seed: int, properties: dict[str, float] | None = None, length: float | None = None) -> DeformableBody:
    """A rope lying on the table along a smooth random curve, centred at the origin.

    Args:
        seed: draws the curve, the length and (when ``properties`` is None) the properties.
        properties: rope properties (default: sampled).
        length: metres (default: drawn in `ROPE_LENGTH`).
    """
    rng = np.random.default_rng(seed)
    total = float(rng.uniform(*ROPE_LENGTH)) if length is None else float(length)
    props = sample_properties("rope", rng) if properties is None else dict(properties)
    verts, tets, normals = rod(centre_line(total, rng), ROPE_RADIUS)
    return DeformableBody("rope", "rope", verts, tets, np.arange(len(verts)), normals, props, seed)
