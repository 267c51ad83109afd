"""The paper's data procedures (appendix, §Dataset) as (contacts, motions) for `simulate`.

- Cloth drag: one or two cloud points, each moved by a horizontal displacement of 15-50 % of the cloth's size in
  a random heading (two points share the heading ± 30°).
- Cloth fold: a fold line through the centre at a random angle; the one or two keypoints farthest from it on one
  side (corners, sleeve ends) move to their mirror images across it (the simulator lifts them on an arc).
- Rope drag: one or two points (the second at least a quarter of the rope away), 10-40 % of the length.
- Plasticine: one or two fingertip presses of upward-facing regions (issue 59's decision: presses the answer can
  express). The surface points are clustered by K-means (``PLASTICINE_CLUSTERS`` = 100 in the paper; at most a
  quarter of the cloud here, our bodies have ~100 surface points); of the clusters whose mean normal n̄ faces up
  (n̄_z > ``UPWARD``), one or two distinct ones are pressed, each at its cloud point nearest the cluster's centre,
  by d = −n̄ · U(0.1, 0.25) · size plus a tangential part up to ``PRESS_TANGENT`` of that, then released. The
  body's base is held by the board meanwhile (`mjcf.held_vertices`), so a press dents rather than slides it. (The
  paper pushes a whole cluster; measured here, two contacts replayed that press in 3 of 20 cases, the fingertip
  press in 20 of 20: research/results/deformables.md.)
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.cluster.vq import kmeans2

from manifoundation.core.deformable.body import DeformableBody

PLASTICINE_CLUSTERS = 100
CLOTH_DRAG = (0.15, 0.5)
ROPE_DRAG = (0.1, 0.4)
PRESS_DEPTH = (0.1, 0.25)
PRESS_TANGENT = 0.2  # the tangential part's largest length, × the press depth
UPWARD = 0.5  # a cluster faces up when its unit mean normal's z exceeds this


@dataclass(frozen=True)
class Manipulation:
    """What a procedure does: cloud indices (H,), their motions (H, 3) m, and the procedure's name."""

    contacts: np.ndarray
    motions: np.ndarray
    procedure: str


def _heading(angle: float) -> np.ndarray:
    return np.array([np.cos(angle), np.sin(angle), 0.0])


def cloth_drag(body: DeformableBody, rng: np.random.Generator) -> Manipulation:
    """One or two points dragged across the table."""
    n = int(rng.integers(1, 3))
    idx = rng.choice(len(body.surface), size=n, replace=False)
    base = rng.uniform(0, 2 * np.pi)
    motions = np.stack([_heading(base + rng.uniform(-0.5, 0.5) * (k > 0)) for k in range(n)])
    motions *= rng.uniform(*CLOTH_DRAG, size=(n, 1)) * body.size
    return Manipulation(idx.astype(np.int64), motions, "cloth_drag")


def cloth_fold(body: DeformableBody, rng: np.random.Generator) -> Manipulation:
    """The farthest keypoints on one side of a random fold line move to their mirror images."""
    pts = body.points
    centre = pts.mean(axis=0)
    normal = _heading(rng.uniform(0, 2 * np.pi))
    side = (pts - centre) @ normal
    n = int(rng.integers(1, 3))
    far = np.argsort(-side)[: max(1, len(pts) // 20)]  # the outermost 5 %: corners, sleeve ends, hems
    picks = [int(far[0])]
    if n == 2:  # the second keypoint: the outermost one far from the first along the fold line
        gap = np.linalg.norm(pts[far] - pts[picks[0]], axis=1)
        picks.append(int(far[np.argmax(gap)]))
    idx = np.unique(np.array(picks, dtype=np.int64))
    motions = -2.0 * side[idx, None] * normal[None]
    return Manipulation(idx, motions, "cloth_fold")


def rope_drag(body: DeformableBody, rng: np.random.Generator) -> Manipulation:
    """One or two rope points dragged; two are at least a quarter of the rope apart."""
    n_pts = len(body.surface)
    first = int(rng.integers(n_pts))
    idx = [first]
    if rng.random() < 0.5:
        far = np.flatnonzero(np.abs(np.arange(n_pts) - first) >= n_pts // 4)
        idx.append(int(rng.choice(far)))
    base = rng.uniform(0, 2 * np.pi)
    length = body.measure()
    motions = np.stack([_heading(base + rng.uniform(-0.4, 0.4) * (k > 0)) for k in range(len(idx))])
    motions *= rng.uniform(*ROPE_DRAG, size=(len(idx), 1)) * length
    return Manipulation(np.array(idx, dtype=np.int64), motions, "rope_drag")


def plasticine_push(body: DeformableBody, rng: np.random.Generator) -> Manipulation:
    """One or two fingertip presses of upward-facing surface regions (see the module doc): contacts (H,) with
    H ∈ {1, 2}, each its own press (H, 3)."""
    pts = body.points
    k = min(PLASTICINE_CLUSTERS, max(2, len(pts) // 4))
    centres, labels = kmeans2(pts, k, minit="++", seed=rng)
    clusters, normals = [], []
    for c in np.unique(labels):
        n = body.normals[labels == c].mean(axis=0)
        n /= max(float(np.linalg.norm(n)), 1e-12)
        if n[2] > UPWARD:
            clusters.append(int(c))
            normals.append(n)
    if not clusters:  # every body has a top; a degenerate clustering falls back to the highest point, straight down
        return _press(np.array([int(np.argmax(pts[:, 2]))]), np.array([[0.0, 0.0, 1.0]]), body.size, rng)
    count = min(int(rng.integers(1, 3)), len(clusters))
    chosen = rng.choice(len(clusters), size=count, replace=False)
    idx = np.array([int(np.argmin(np.linalg.norm(pts - centres[clusters[j]], axis=1))) for j in chosen])
    idx, first = np.unique(idx, return_index=True)  # two centres nearest one point: one press
    return _press(idx, np.stack([normals[chosen[j]] for j in first]), body.size, rng)


def _press(idx: np.ndarray, normals: np.ndarray, size: float, rng: np.random.Generator) -> Manipulation:
    """Presses of cloud points ``idx`` (H,) along their −normals (H, 3), each 0.1-0.25 × ``size`` deep with a
    tangential part up to `PRESS_TANGENT` of that."""
    motions = []
    for n in normals:
        depth = rng.uniform(*PRESS_DEPTH) * size
        t = rng.normal(size=3)
        t -= (t @ n) * n
        t *= rng.uniform(0, PRESS_TANGENT) * depth / max(float(np.linalg.norm(t)), 1e-12)
        motions.append(-n * depth + t)
    return Manipulation(idx.astype(np.int64), np.stack(motions), "plasticine_push")


def random_manipulation(body: DeformableBody, rng: np.random.Generator) -> Manipulation:
    """The material's procedure (cloth: drag or fold, half each)."""
    if body.material == "cloth":
        return cloth_fold(body, rng) if rng.random() < 0.5 else cloth_drag(body, rng)
    if body.material == "rope":
        return rope_drag(body, rng)
    return plasticine_push(body, rng)
