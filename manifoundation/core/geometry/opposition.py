"""Opposed contact sets for "hold it": a thumb contact facing the other fingertips' contacts across the object.

A position-controlled hand squeezes by driving every contact a little further inward along its normal (the field's
test: 1 cm). The object stays where it is only if those pushes balance, in force *and* torque; friction alone
(what force closure allows) does not keep a squeezed object in place — on third-party objects the refinement's
friction-closure answers had a median unit-normal imbalance ‖Σ n_i‖ / m of 0.31, and the object turned or slid
out of the hand under the squeeze in most of them (research/results/physics.md).

`opposed_contacts` therefore proposes contact sets whose normals cancel by construction:

1. a thumb point ``a`` and, along its inward normal, an opposite point ``b`` whose normal points the other way
   (``n_a · n_b ≤ −cos 30°``, the segment a→b within 30° of −n_a), at most ``max_width`` apart;
2. the other fingertips on ``b``'s face (normals within 30° of ``n_b``), laid symmetrically about ``b`` at the
   hand's finger spacing (at least half of it) along the face's long tangent direction, so their pushes have no
   net torque about the line a–b.

Pairs are drawn with probability ∝ weight × opposition (the weight: a heatmap, or uniform). Pure numpy, a few
milliseconds for 2 048 points.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

OPPOSED_COS = np.cos(np.deg2rad(30.0))
"""Normals count as opposed below −this dot product; a face's points lie within this of the face normal."""


@dataclass(frozen=True)
class OpposedContacts:
    """One opposed set: ``indices`` (m,) into the cloud, thumb first; ``width`` (m) across a–b; ``imbalance``
    = ‖Σ n_i‖ / m of the set's normals."""

    indices: np.ndarray
    width: float
    imbalance: float


def opposed_contacts(
    points: np.ndarray,
    normals: np.ndarray,
    count: int,
    spacing: float,
    max_width: float,
    sets: int,
    rng: np.random.Generator,
    weight: np.ndarray | None = None,
    allowed: np.ndarray | None = None,
) -> list[OpposedContacts]:
    """Up to ``sets`` opposed contact sets of ``count`` points (thumb first), best-drawn first.

    Args:
        points: (N, 3) surface points. normals: (N, 3) outward unit normals.
        count: fingertips m (≥ 2).
        spacing: distance (m) between neighbouring non-thumb fingertips (the hand's at rest).
        max_width: the widest a–b distance (m) the hand can span.
        sets: how many sets to return (distinct thumb points).
        rng: randomness of the draw.
        weight: (N,) non-negative preference of each point (e.g. a contact heatmap); None: uniform.
        allowed: (N,) bool, the points contacts may lie on (a region); None: all.

    Returns:
        Sets ordered by how they were drawn (most probable first); empty when no point has an opposite within
        ``max_width``.
    """
    pts = np.asarray(points, dtype=np.float64)
    nrm = np.asarray(normals, dtype=np.float64)
    nrm = nrm / np.maximum(np.linalg.norm(nrm, axis=1, keepdims=True), 1e-12)
    ok = np.ones(len(pts), bool) if allowed is None else np.asarray(allowed, bool)
    w = np.ones(len(pts)) if weight is None else np.clip(np.asarray(weight, dtype=np.float64), 0.0, None) + 1e-3
    pairs = _opposite_pairs(pts, nrm, ok, max_width)
    if not pairs:
        return []
    a_idx = np.array([a for a, _, _ in pairs])
    b_idx = np.array([b for _, b, _ in pairs])
    quality = np.array([q for _, _, q in pairs])
    p = w[a_idx] * w[b_idx] * quality
    p = p / p.sum()
    order = rng.choice(len(pairs), size=len(pairs), replace=False, p=p)
    tree = cKDTree(pts)
    out: list[OpposedContacts] = []
    used: set[int] = set()
    for k in order:
        a, b = int(a_idx[k]), int(b_idx[k])
        if a in used:
            continue
        fingers = _face_row(pts, nrm, ok, tree, b, count - 1, spacing)
        if fingers is None:
            continue
        idx = np.array([a, *fingers])
        used.add(a)
        out.append(OpposedContacts(idx, float(np.linalg.norm(pts[b] - pts[a])),
                                   float(np.linalg.norm(nrm[idx].sum(axis=0)) / len(idx))))  # fmt: skip
        if len(out) == sets:
            break
    return out


def _opposite_pairs(
    pts: np.ndarray, nrm: np.ndarray, ok: np.ndarray, max_width: float, candidates: int = 256
) -> list[tuple[int, int, float]]:
    """(a, b, quality) for up to ``candidates`` thumb points a spread over the cloud: b the best opposite of a
    (quality = −n_a·n_b × cos of the segment's angle to −n_a), or none."""
    ids = np.flatnonzero(ok)
    if len(ids) < 2:
        return []
    step = max(1, len(ids) // candidates)
    out = []
    for a in ids[::step]:
        d = pts[ids] - pts[a]
        dist = np.linalg.norm(d, axis=1)
        along = d @ -nrm[a]
        opposed = -(nrm[ids] @ nrm[a])
        fit = (dist > 1e-3) & (dist <= max_width) & (opposed >= OPPOSED_COS) & (along >= OPPOSED_COS * dist)
        if not fit.any():
            continue
        score = np.where(fit, opposed * along / np.maximum(dist, 1e-9), -np.inf)
        j = int(np.argmax(score))
        out.append((int(a), int(ids[j]), float(score[j])))
    return out


def _face_row(
    pts: np.ndarray, nrm: np.ndarray, ok: np.ndarray, tree: cKDTree, b: int, fingers: int, spacing: float
) -> list[int] | None:
    """``fingers`` points of b's face laid symmetrically about b at ``spacing`` along the face's long direction
    (down to half of it where the face is narrower); None when the face has too few points or b lies too near its
    edge for that."""
    if fingers == 1:
        return [b]
    near = np.array(tree.query_ball_point(pts[b], r=spacing * (fingers - 1) / 2 + 0.5 * spacing))
    face = near[ok[near] & (nrm[near] @ nrm[b] >= OPPOSED_COS)]
    if len(face) < fingers:
        return None
    rel = pts[face] - pts[b]
    rel -= np.outer(rel @ nrm[b], nrm[b])  # in b's tangent plane
    long_axis = np.linalg.svd(rel, full_matrices=False)[2][0]
    coords = rel @ long_axis
    half = spacing * (fingers - 1) / 2
    reach = min(half, float(min(coords.max(), -coords.min())))
    if reach < 0.5 * half:  # b near the face's edge: the fingers would crowd (or hang over it)
        return None
    offsets = np.linspace(-reach, reach, fingers)
    chosen: list[int] = []
    for o in offsets:
        target = pts[b] + o * long_axis
        dist = np.linalg.norm(pts[face] - target, axis=1)
        dist[np.isin(face, chosen)] = np.inf
        chosen.append(int(face[int(np.argmin(dist))]))
    return chosen
