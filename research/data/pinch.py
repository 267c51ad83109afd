"""Palm poses that pinch the object across an antipodal pair (force-closure grasp sampling).

The facing palms of `sampling.sample_palms` put every fingertip on the side of the object the palm faces, so on
objects larger than the hand they seldom give force closure. Here the palm is placed so that the hand's
*opposition axis* — from the opposing fingertip (thumb; for grippers, one finger) to the mean of the others, at
the rest pose — lies along an antipodal segment of the object, centred on it:

1. a surface point p₁ with outward normal n₁; a ray into the object along −n₁ gives its exit point p₂ (the
   mesh's first hit), width w = ‖p₂ − p₁‖;
2. keep the pair when both friction cones (μ) contain the segment (n₂·(−n₁) ≥ cos atan μ) and w fits the hand
   (w ≤ rest aperture + ``APERTURE_SLACK``);
3. rotate the opposition axis onto the segment (the thumb on p₁ or p₂ at random), random roll about it, and put
   the midpoint of the rest opposition pair on the midpoint of the segment.

The per-finger IK of `sampling.sample_grasps` then closes the fingertips onto the surface around them.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from scipy.spatial.transform import Rotation

from manifoundation.core.refine.initialise import opposition, rest_geometry
from research.data.checks import ObjectField

if TYPE_CHECKING:
    from manifoundation.core.robots.hand import Hand

APERTURE_SLACK = 0.03  # m: the fingers may open a little beyond the rest pose
RAYS_PER_PALM = 8  # candidate surface points per wanted palm (most rays fail the width or cone test)


def hand_opposition(hand: Hand) -> tuple[np.ndarray, np.ndarray, float]:
    """Thumb tip (3,), mean of the other tips (3,) at rest in the palm frame, and their distance (the aperture);
    `manifoundation.core.refine.initialise.opposition`."""
    thumb, others = opposition(rest_geometry(hand))
    return thumb, others, float(np.linalg.norm(others - thumb))


def antipodal_pairs(
    obj: ObjectField, count: int, mu: float, max_width: float, rng: np.random.Generator
) -> tuple[np.ndarray, np.ndarray]:
    """Up to ``count`` antipodal surface pairs (K, 3), (K, 3) no wider than ``max_width`` (module doc, 1–2)."""
    idx = rng.integers(len(obj.points), size=count)
    p1, n1 = obj.points[idx], obj.normals[idx]
    hits, rays, faces = obj.mesh.ray.intersects_location(p1 - 1e-4 * n1, -n1, multiple_hits=False)
    if not len(rays):
        return np.zeros((0, 3)), np.zeros((0, 3))
    p2, n2 = np.asarray(hits), np.asarray(obj.mesh.face_normals)[faces]
    a = p1[rays]
    width = np.linalg.norm(p2 - a, axis=1)
    cone = np.einsum("ij,ij->i", n2, -n1[rays]) >= np.cos(np.arctan(mu))
    keep = cone & (width <= max_width) & (width > 1e-3)
    return a[keep], p2[keep]


def sample_pinch_palms(
    hand: Hand, obj: ObjectField, count: int, mu: float, rng: np.random.Generator
) -> tuple[np.ndarray, np.ndarray]:
    """Up to ``count`` pinching palm poses: positions (B, 3), quaternions (B, 4) wxyz (B = 0 when the object
    has no antipodal pair the hand spans)."""
    thumb, others, aperture = hand_opposition(hand)
    p1, p2 = antipodal_pairs(obj, RAYS_PER_PALM * count, mu, aperture + APERTURE_SLACK, rng)
    p1, p2 = p1[:count], p2[:count]
    axis_h = (others - thumb) / aperture
    mid_h = 0.5 * (thumb + others)
    positions, quats = np.zeros((len(p1), 3)), np.zeros((len(p1), 4))
    for b in range(len(p1)):
        a, c = (p1[b], p2[b]) if rng.random() < 0.5 else (p2[b], p1[b])
        d = (c - a) / np.linalg.norm(c - a)
        align, _ = Rotation.align_vectors(d[None], axis_h[None])
        rot = Rotation.from_rotvec(d * rng.uniform(-np.pi, np.pi)) * align
        positions[b] = 0.5 * (a + c) - rot.apply(mid_h)
        x, y, z, w = rot.as_quat()
        quats[b] = (w, x, y, z)
    return positions, quats
