"""The point hierarchy shared by the object encoder φ_o and the posterior φ_q.

Sampling and neighbourhoods depend only on the object's coordinates, so they are computed once per forward
pass (nested FPS: level l's centroids are drawn from level l-1's points) and reused by every PointNet++ that
runs over the same cloud.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import torch

from models.network.config import LevelConfig
from models.network.point_ops import ball_query, farthest_point_sample, gather_points, three_nn


@dataclass
class PointHierarchy:
    """Coordinates and index maps of every level (level 0 is the input cloud).

    Attributes:
        xyz: per level l = 0..L, (B, n_l, 3).
        groups: per level l = 1..L, (B, n_l, k_l) neighbour indices into level l-1.
        radii: per level l = 1..L, the ball radius.
        up_idx, up_weights: per level l = 1..L, (B, n_{l-1}, 3) 3-NN indices into level l and their weights,
            used to propagate level l's features back to level l-1.
    """

    xyz: list[torch.Tensor]
    groups: list[torch.Tensor]
    radii: list[float]
    up_idx: list[torch.Tensor]
    up_weights: list[torch.Tensor]


@torch.no_grad()
def build_hierarchy(xyz: torch.Tensor, levels: Sequence[LevelConfig]) -> PointHierarchy:
    """Sample and group ``xyz`` (B, N, 3) level by level."""
    h = PointHierarchy(xyz=[xyz], groups=[], radii=[], up_idx=[], up_weights=[])
    for lv in levels:
        prev = h.xyz[-1]
        centres = gather_points(prev, farthest_point_sample(prev, min(lv.npoint, prev.shape[1])))
        h.xyz.append(centres)
        h.groups.append(ball_query(prev, centres, lv.radius, lv.nsample))
        h.radii.append(lv.radius)
        idx, w = three_nn(prev, centres)
        h.up_idx.append(idx)
        h.up_weights.append(w)
    return h
