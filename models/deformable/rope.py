"""Ropes: a smooth random curve lying on the table, as a chain of edges (MuJoCo 1D flex).

The curve's heading is θ(s) = θ₀ + Σ_k a_k sin(k π s + φ_k), k = 1..3, a_k ~ U(−``CURL``, ``CURL``)/k; integrating
unit steps along it gives the centre line, resampled to ``vertices`` points (at least 64: the contract's minimum
cloud). Lengths are drawn in ``ROPE_LENGTH``; the stiffness (Young's modulus) in `materials.RANGES`.
"""

from __future__ import annotations

import numpy as np

from models.deformable.body import DeformableBody
from models.deformable.materials import ROPE_RADIUS, sample_properties

ROPE_LENGTH = (0.3, 0.9)  # m
CURL = 1.2  # rad: largest heading swing of the first mode
ROPE_KINDS = ("rope",)


def make_rope(seed: int, properties: dict[str, float] | None = None, length: float | None = None,
              vertices: int = 72) -> DeformableBody:  # fmt: skip
    """A rope lying on the table along a smooth random curve, centred at the origin.

    Args:
        seed: draws the curve, the length and (when ``properties`` is None) the properties.
        properties: rope properties (default: sampled).
        length: metres (default: drawn in `ROPE_LENGTH`).
        vertices: points on the centre line (≥ 64).
    """
    if vertices < 64:
        raise ValueError(f"vertices: {vertices}, need at least 64 (the contract's smallest cloud)")
    rng = np.random.default_rng(seed)
    total = float(rng.uniform(*ROPE_LENGTH)) if length is None else float(length)
    props = sample_properties("rope", rng) if properties is None else dict(properties)
    s = np.linspace(0.0, 1.0, vertices)
    theta = np.full_like(s, rng.uniform(0, 2 * np.pi))
    for k in range(1, 4):
        theta += rng.uniform(-CURL, CURL) / k * np.sin(k * np.pi * s + rng.uniform(0, 2 * np.pi))
    step = total / (vertices - 1)
    xy = np.vstack([[0.0, 0.0], np.cumsum(step * np.column_stack([np.cos(theta[:-1]), np.sin(theta[:-1])]), axis=0)])
    xy -= xy.mean(axis=0)
    pts = np.column_stack([xy, np.full(vertices, ROPE_RADIUS)])
    edges = np.column_stack([np.arange(vertices - 1), np.arange(1, vertices)])
    normals = np.tile([0.0, 0.0, 1.0], (vertices, 1))
    return DeformableBody("rope", "rope", pts, edges, np.arange(vertices), normals, props, seed)
