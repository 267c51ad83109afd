"""Contact selection: non-maximum suppression on the heatmap over the point cloud (paper §III-A).

Greedy NMS in the request's frame:

1. Candidates are the points whose region-mask entry is True and whose heatmap value is ≥ τ, with
   τ = min(``threshold``, b + ``relative`` · (peak − b)), peak the highest and b the median heat among the
   allowed points; a heatmap whose peak stands less than ``min_contrast`` above its median (flat: the network
   marks no place) keeps τ = ``threshold``. The relative part makes selection independent of the network's
   calibration: a CVAE decoded from a prior sample blurs between modes, so its peaks often sit under 0.5
   while still marking the right places (the training log's ``hit`` column measures that).
   ``relative=None`` gives the plain absolute threshold.
   The mask is a hard constraint: a masked-out point is never a contact, whatever the network predicted.
2. Take the highest remaining candidate as a peak. Its group is the remaining candidates within ``radius``
   of it (the peak included). If the group has fewer than ``min_group_size`` points the peak is an isolated
   spike: drop it alone and go on. Otherwise accept the peak as a contact and remove its whole group.
3. Stop after ``max_contacts`` contacts (H ≤ the hand's fingertip count) or when no candidate is left.

The contact's force/motion is the force map's vector at the peak point (the paper selects "the forces/motions
on the chosen contact points"). ``radius`` defaults to :data:`DEFAULT_RADIUS_FRACTION` of the cloud's longest
bounding-box side, so it scales with the object; pass an absolute radius (request units) to override.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

DEFAULT_THRESHOLD = 0.5
DEFAULT_RELATIVE = 0.5
DEFAULT_MIN_CONTRAST = 0.1
DEFAULT_RADIUS_FRACTION = 0.1
DEFAULT_MIN_GROUP_SIZE = 3
# the least heat a motion map is divided by when a contact's motion is read as map / heat (the network's own
# estimate of a deformable contact's motion; the read-out loss in manifoundation.core.network.loss trains that quotient)
HEAT_FLOOR = 0.1


@dataclass(frozen=True)
class ContactSelection:
    """Up to H contacts, best first.

    Attributes:
        indices: (H,) int64 point indices into the request's cloud.
        points: (H, 3) contact positions.
        forces: (H, 3) force/motion vectors at the contacts (request units).
        scores: (H,) heatmap values at the contacts.
    """

    indices: np.ndarray
    points: np.ndarray
    forces: np.ndarray
    scores: np.ndarray

    def __len__(self) -> int:
        return int(self.indices.shape[0])


def select_contacts(
    points: np.ndarray,
    heatmap: np.ndarray,
    forces: np.ndarray,
    mask: np.ndarray | None,
    max_contacts: int,
    *,
    radius: float | None = None,
    threshold: float = DEFAULT_THRESHOLD,
    relative: float | None = DEFAULT_RELATIVE,
    min_contrast: float = DEFAULT_MIN_CONTRAST,
    min_group_size: int = DEFAULT_MIN_GROUP_SIZE,
) -> ContactSelection:
    """Select at most ``max_contacts`` contacts by NMS (see the module docstring).

    Args:
        points: (N, 3) object points.
        heatmap: (N,) contact heatmap (one latent sample).
        forces: (N, 3) force/motion map of the same sample.
        mask: (N,) bool region mask (True = allowed), or None for no constraint.
        max_contacts: H, at most the number of fingertips; 0 gives an empty selection.
        radius: suppression radius in the cloud's units; default 0.1 × the longest bounding-box side.
        threshold: heatmap value that always qualifies a point as a candidate.
        relative: candidates also qualify at ≥ median + ``relative`` × (peak − median) (None: absolute only).
        min_contrast: with ``relative``, a peak less than this above the median selects nothing.
        min_group_size: minimum number of candidates within ``radius`` of a peak (peak included).

    Returns:
        The selection (possibly empty).
    """
    pts = np.asarray(points, dtype=np.float64)
    heat = np.asarray(heatmap, dtype=np.float64)
    n = pts.shape[0]
    if heat.shape != (n,) or np.shape(forces) != (n, 3):
        raise ValueError(f"heatmap must be ({n},) and forces ({n}, 3), got {heat.shape} and {np.shape(forces)}")
    if max_contacts < 0 or min_group_size < 1:
        raise ValueError("max_contacts must be ≥ 0 and min_group_size ≥ 1")
    allowed = np.ones(n, dtype=bool) if mask is None else np.asarray(mask, dtype=bool)
    if allowed.shape != (n,):
        raise ValueError(f"mask must be ({n},), got {allowed.shape}")
    if radius is None:
        radius = DEFAULT_RADIUS_FRACTION * float(np.ptp(pts, axis=0).max()) if n else 0.0
    tau = threshold
    if relative is not None and allowed.any():
        base, peak = float(np.median(heat[allowed])), float(heat[allowed].max())
        if peak - base >= min_contrast:
            tau = min(threshold, base + relative * (peak - base))
    cand = np.flatnonzero(allowed & (heat >= tau))
    chosen: list[int] = []
    if cand.size and max_contacts > 0:
        tree = cKDTree(pts[cand])
        alive = np.ones(cand.size, dtype=bool)
        for local in np.argsort(-heat[cand], kind="stable"):
            if not alive[local]:
                continue
            group = [g for g in tree.query_ball_point(pts[cand[local]], r=radius) if alive[g]]
            if len(group) < min_group_size:
                alive[local] = False
                continue
            chosen.append(int(cand[local]))
            alive[group] = False
            if len(chosen) == max_contacts:
                break
    idx = np.asarray(chosen, dtype=np.int64)
    return ContactSelection(
        indices=idx,
        points=pts[idx].reshape(-1, 3),
        forces=np.asarray(forces, dtype=np.float64)[idx].reshape(-1, 3),
        scores=heat[idx],
    )
