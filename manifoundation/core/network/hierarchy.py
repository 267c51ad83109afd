"""The point hierarchy shared by the object encoder φ_o and the posterior φ_q.

Sampling and neighbourhoods depend only on the object's coordinates, so they are computed once per forward
pass (nested FPS: level l's centroids are drawn from level l-1's points) and reused by every PointNet++ that
runs over the same cloud. Training precomputes the index maps once per object (:func:`index_hierarchy`) and
gathers each batch's hierarchy from them (:func:`gather_hierarchy`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import torch
from scipy.spatial import cKDTree

from manifoundation.core.network.config import LevelConfig
from manifoundation.core.network.point_ops import (
    ball_query,
    farthest_point_sample,
    farthest_point_sample_np,
    gather_points,
    three_nn,
)


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


@dataclass(frozen=True)
class HierarchyIndex:
    """The index maps of one cloud's hierarchy, without coordinates (numpy, per object, reusable).

    Farthest point sampling, the neighbour ranking and the 3-NN maps depend only on distances between the
    cloud's points, so they are unchanged by a rotation, a translation or a uniform scale: a training example
    computes them once per object and applies each augmentation's normalisation to the coordinates alone
    (:func:`gather_hierarchy`). Only the ball query's radius depends on the scale; it is applied then.

    Attributes:
        samples: per level l = 1..L, (n_l,) indices into level l-1 (nested FPS).
        neighbours: per level l = 1..L, (n_l, k_l) the k nearest level l-1 points of each centroid, nearest first.
        up_idx: per level l = 1..L, (n_{l-1}, 3) the 3 nearest level-l centroids of each level l-1 point.
    """

    samples: tuple[np.ndarray, ...]
    neighbours: tuple[np.ndarray, ...]
    up_idx: tuple[np.ndarray, ...]


def index_hierarchy(points: np.ndarray, levels: Sequence[LevelConfig]) -> HierarchyIndex:
    """The :class:`HierarchyIndex` of one cloud (N, 3), as :func:`build_hierarchy` samples and groups it."""
    samples, neighbours, up = [], [], []
    prev = np.asarray(points, dtype=np.float32)
    for lv in levels:
        keep = farthest_point_sample_np(prev, min(lv.npoint, len(prev)))
        centres = prev[keep]
        tree = cKDTree(prev)
        k = min(lv.nsample, len(prev))
        nb = tree.query(centres, k=k)[1].reshape(len(centres), k)
        if k < lv.nsample:
            nb = np.concatenate([nb, np.repeat(nb[:, :1], lv.nsample - k, axis=1)], axis=1)
        k_up = min(3, len(centres))
        samples.append(keep)
        neighbours.append(nb.astype(np.int64))
        up.append(cKDTree(centres).query(prev, k=k_up)[1].reshape(len(prev), k_up).astype(np.int64))
        prev = centres
    return HierarchyIndex(tuple(samples), tuple(neighbours), tuple(up))


@torch.no_grad()
def gather_hierarchy(
    xyz: torch.Tensor, index: Sequence[HierarchyIndex], levels: Sequence[LevelConfig]
) -> PointHierarchy:
    """The :class:`PointHierarchy` of ``xyz`` (B, N, 3) from each object's precomputed index.

    Equal to :func:`build_hierarchy` of the same clouds (up to distance ties): a neighbour farther than the
    level's radius is replaced by the nearest one, and the 3-NN weights are the inverse squared distances.
    """
    h = PointHierarchy(xyz=[xyz], groups=[], radii=[], up_idx=[], up_weights=[])
    for li, lv in enumerate(levels):
        prev = h.xyz[-1]

        def stack(key: str, li: int = li) -> torch.Tensor:
            return torch.from_numpy(np.stack([getattr(ix, key)[li] for ix in index])).to(xyz.device)

        centres = gather_points(prev, stack("samples"))
        nb = stack("neighbours")
        far = (gather_points(prev, nb) - centres.unsqueeze(2)).square().sum(-1) > lv.radius**2
        h.xyz.append(centres)
        h.groups.append(torch.where(far, nb[..., :1], nb))
        h.radii.append(lv.radius)
        up = stack("up_idx")
        d2 = (gather_points(centres, up) - prev.unsqueeze(2)).square().sum(-1)
        w = 1.0 / (d2 + 1e-8)
        h.up_idx.append(up)
        h.up_weights.append(w / w.sum(dim=-1, keepdim=True))
    return h
