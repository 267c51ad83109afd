"""The service's answer for a deformable object: contacts from the network's heatmap, a post-contact motion each.

For each latent sample k: NMS on the heatmap (`manifoundation.core.network.selection.select_contacts`, the region mask
hard) picks H ≤ ``max_contacts`` contacts; the motion of each is the task's own displacement at that point (a grasped
point goes where the gripper takes it, so the target says exactly where it must end). The network's motion map
(its φ_f map, motion map / heat) estimates the same vector; measured on unseen cloth bodies at the same contacts,
the target's displacement reached the target more often (85.6 against 79.4 % per sample) and never less, rope
the same (docs/deformables.md, "The motion at a network contact"). No hand refinement: a deformable is moved by
grasping its points, not by balancing a wrench. A heatmap with no peak gives no network contacts; the answer then
takes the H allowed points that the target moves most, spread apart (`moving_indices`), with the target motion at
them, and says ``motion_fallback``.

A body slid as a whole (every point's target motion about the same d) is pulled through its centre line: of the
heatmap's peaks, the H contacts (the highest peak among them) whose mean lies nearest the line along d through
the cloud's centroid (`balanced_peaks`). Measured on the property figure's handkerchiefs: every network answer
whose two contacts sat on one side of that line failed, every one straddling it reached the slid square.
"""

from __future__ import annotations

from dataclasses import dataclass
from itertools import combinations

import numpy as np

from manifoundation.core.deformable.slides import along_and_across
from manifoundation.core.network.selection import select_contacts

TASK_KINDS = ("point_motion", "target_points")
UNIFORM_MOTION = 0.1  # a slide: the points' motions differ from their mean by at most this × its length (mean)
BALANCE_PEAKS = 8  # heatmap peaks a slide's contacts are chosen from


@dataclass(frozen=True)
class DeformableContacts:
    """One proposal: cloud indices (H,), points (H, 3), post-contact motions (H, 3) m, and their source."""

    indices: np.ndarray
    points: np.ndarray
    motions: np.ndarray
    source: str


def is_slide(target_motion: np.ndarray) -> bool:
    """The target moves every point (N, 3) by about the same displacement (`UNIFORM_MOTION`), and does move it."""
    m = np.asarray(target_motion, dtype=np.float64)
    mean = m.mean(axis=0)
    size = float(np.linalg.norm(mean))
    return size > 0.0 and float(np.linalg.norm(m - mean, axis=1).mean()) <= UNIFORM_MOTION * size


def balanced_peaks(points: np.ndarray, peaks: np.ndarray, count: int, displacement: np.ndarray) -> np.ndarray:
    """Positions into ``peaks`` (H', 3; heat order) of the ``count`` peaks, the first among them, whose mean lies
    nearest the line through the centroid of ``points`` (N, 3) along ``displacement`` (3,) (horizontal distance;
    ties: the higher peaks)."""
    _, across = along_and_across(peaks, displacement, origin=np.asarray(points, dtype=np.float64).mean(axis=0))
    best, best_offset = np.arange(count), np.inf
    for rest in combinations(range(1, len(peaks)), count - 1):
        chosen = np.array((0, *rest))
        offset = abs(float(across[chosen].mean()))
        if offset < best_offset - 1e-12:
            best, best_offset = chosen, offset
    return best


def spread_indices(points: np.ndarray, allowed: np.ndarray, count: int, rng: np.random.Generator) -> np.ndarray:
    """``count`` indices of ``allowed`` points spread by farthest-point sampling from a random start."""
    pick = [int(rng.choice(allowed))]
    dist = np.linalg.norm(points[allowed] - points[pick[0]], axis=1)
    while len(pick) < min(count, len(allowed)):
        nxt = int(allowed[int(np.argmax(dist))])
        pick.append(nxt)
        dist = np.minimum(dist, np.linalg.norm(points[allowed] - points[nxt], axis=1))
    return np.array(pick, dtype=np.int64)


def moving_indices(
    points: np.ndarray, allowed: np.ndarray, motion: np.ndarray, count: int, rng: np.random.Generator | None = None
) -> np.ndarray:
    """``count`` indices of ``allowed`` points that the motion moves most, spread apart: first the most-moved
    point (with ``rng``: a random one of those moved at least 80 % as much, for another proposal), then each time
    the point maximising |m_i| · min(1, d_i / r), d_i its distance to the points taken and r a quarter of the
    cloud's size (so a second contact is not the first one's neighbour unless nothing else moves), ties going to
    the farthest point. With an equal motion everywhere it is farthest-point sampling from the first point.

    Args:
        points: (N, 3). allowed: (A,) candidate indices. motion: (N, 3) per-point target motion. count: H.
        rng: draws the first point (None: the most-moved one).
    """
    cloud = np.asarray(points, dtype=np.float64)
    moved = np.linalg.norm(np.asarray(motion, dtype=np.float64)[allowed], axis=1)
    candidates = cloud[allowed]
    reach = 0.25 * float(np.linalg.norm(np.ptp(cloud, axis=0)))
    first = int(np.argmax(moved)) if rng is None else int(rng.choice(np.flatnonzero(moved >= 0.8 * moved.max())))
    pick = [first]
    dist: np.ndarray = np.linalg.norm(candidates - candidates[first], axis=1)
    while len(pick) < min(count, len(allowed)):
        near = dist / max(reach, 1e-12)
        score: np.ndarray = moved * np.minimum(1.0, near) * (1.0 + 1e-3 * near)  # ties: the farthest point
        score[pick] = -1.0
        nxt = int(np.argmax(score))
        pick.append(nxt)
        dist = np.minimum(dist, np.linalg.norm(candidates - candidates[nxt], axis=1))
    chosen: np.ndarray = np.asarray(allowed, dtype=np.int64)[pick]
    return chosen


def deformable_contacts(
    points: np.ndarray,
    heatmap: np.ndarray,
    target_motion: np.ndarray,
    mask: np.ndarray | None,
    max_contacts: int,
    rng: np.random.Generator | None = None,
) -> DeformableContacts:
    """Contacts and post-contact motions of one latent sample.

    Args:
        points: (N, 3) cloud. heatmap: (N,) predicted contact heat.
        target_motion: (N, 3) the task's per-point motion: the contacts' motions, and the fallback's places.
        mask: (N,) bool allowed region or None. max_contacts: H, e.g. the hand's fingertips.
        rng: draws the fallback's first point (None: the most-moved one; see `moving_indices`).
    """
    motion = np.asarray(target_motion, dtype=np.float64)
    slide = is_slide(motion)
    # greedy NMS: its first H peaks of more are the H it would pick alone
    peaks = select_contacts(points, heatmap, motion, mask, max(BALANCE_PEAKS, max_contacts) if slide
                            else max_contacts)  # fmt: skip
    count = min(max_contacts, len(peaks))
    keep = np.arange(count)
    if slide and count > 1:
        keep = balanced_peaks(points, peaks.points, count, motion.mean(axis=0))
    if count:
        idx = peaks.indices[keep]
        return DeformableContacts(idx, points[idx], motion[idx], "network")
    allowed = np.flatnonzero(mask) if mask is not None else np.arange(len(points))
    idx = moving_indices(points, allowed, motion, max_contacts, rng)
    return DeformableContacts(idx, points[idx], motion[idx], "motion_fallback")
