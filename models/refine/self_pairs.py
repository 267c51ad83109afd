"""The self-collision pairs that can be near at a pose, found per pair of bodies, not per pair of spheres.

LEAP has 8 513 sphere pairs; the step only uses those with a gap below its ``pair_margin`` and the merit those
that overlap. Each body's spheres lie in a ball (centre and radius in the body frame, built once per hand), so the
gap of any sphere pair between bodies a and b is at least ``|c_a − c_b| − R_a − R_b``: the pairs of body pairs whose
bound exceeds ``PAIR_REACH`` cannot matter and are not measured. The pairs kept are in the hand's order, so the
rows the step builds from them are the same rows in the same order.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from models.robots.hand import Hand

PAIR_REACH = 0.02
"""m: sphere pairs whose gap may be below this are measured (≥ the step's ``pair_margin``, 0.01 m)."""


@dataclass(frozen=True)
class BodyPairBounds:
    """Per body carrying spheres: its index in the tree (B,), the centre (B, 3) and radius (B,) of a ball holding
    its spheres (body frame); per sphere pair (P,) the index of its body pair in ``group_bodies`` (G, 2) (rows of
    the B bodies)."""

    bodies: np.ndarray
    centres: np.ndarray
    radii: np.ndarray
    pair_group: np.ndarray
    group_bodies: np.ndarray

    @classmethod
    def of(cls, hand: Hand) -> BodyPairBounds:
        """The bounds of ``hand`` (cached on it)."""
        cached = hand.__dict__.get("_body_pair_bounds")
        if cached is None:
            sphere_body = np.asarray([hand.tree.body_names.index(link) for link in hand.sphere_links], dtype=np.int64)
            cached = hand.__dict__["_body_pair_bounds"] = cls.build(
                sphere_body, np.asarray(hand.sphere_centres, dtype=np.float64),
                np.asarray(hand.sphere_radii, dtype=np.float64), np.asarray(hand.self_collision_pairs).reshape(-1, 2),
            )  # fmt: skip
        result: BodyPairBounds = cached
        return result

    @classmethod
    def build(
        cls, sphere_body: np.ndarray, centres: np.ndarray, radii: np.ndarray, pairs: np.ndarray
    ) -> BodyPairBounds:
        """From each sphere's body (S,), centre in that body's frame (S, 3) and radius (S,), and the pairs (P, 2)."""
        bodies, row = np.unique(sphere_body, return_inverse=True)
        ball_c = np.stack([centres[row == b].mean(axis=0) for b in range(len(bodies))]).reshape(-1, 3)
        reach = np.linalg.norm(centres - ball_c[row], axis=1) + radii
        ball_r = np.array([reach[row == b].max() for b in range(len(bodies))])
        a, b = row[pairs[:, 0]], row[pairs[:, 1]]
        key = np.minimum(a, b) * len(bodies) + np.maximum(a, b)
        groups, pair_group = np.unique(key, return_inverse=True)
        group_bodies = np.stack([groups // max(len(bodies), 1), groups % max(len(bodies), 1)], axis=1)
        return cls(bodies, ball_c, ball_r, pair_group.reshape(-1), group_bodies)

    def near(self, body_poses: np.ndarray, reach: float = PAIR_REACH) -> np.ndarray:
        """Indices (sorted) of the sphere pairs whose gap may be below ``reach`` at body poses (nb, 4, 4)."""
        T = body_poses[self.bodies]
        world = np.einsum("bij,bj->bi", T[:, :3, :3], self.centres) + T[:, :3, 3]
        a, b = self.group_bodies[:, 0], self.group_bodies[:, 1]
        bound = np.linalg.norm(world[a] - world[b], axis=1) - self.radii[a] - self.radii[b]
        return np.flatnonzero((bound < reach + 1e-9)[self.pair_group])
