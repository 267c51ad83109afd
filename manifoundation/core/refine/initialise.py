"""Pose initialisation (paper §III-B-1): finger↔contact assignments, rigid fit, heatmap IoU.


For H contacts and m fingertips every injective assignment (m!/(m−H)!) is tried. The hand is kept rigid in its
rest pose and the palm pose that brings the assigned fingertips onto the contacts is fitted by a weighted Wahba /
Kabsch problem that also aligns the palm's approach axis with a desired approach direction d. The extra vector
pair makes the fit well posed where fingertips alone are not (two-finger grippers: rotation about the line
through the contacts; one contact): d is the mean inward contact normal −Σn_i/|Σn_i| when the contacts agree,
else (antipodal contacts) each of 6 directions perpendicular to the contacts' principal axis is tried. Every fit
is then backed off along −d until no non-fingertip sphere penetrates the object, and scored by the IoU between
the heatmap its fingertips make (object points within ``radius`` of a fingertip) and the predicted one
(thresholded at 0.5), ties broken by the fit error. All of it is numpy on rest-pose data: ~0.1 ms per fit.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import torch
from scipy.spatial import cKDTree
from scipy.spatial.transform import Rotation

from manifoundation.core.refine.field import PointCloudField
from manifoundation.core.refine.state import HandPose

if TYPE_CHECKING:
    from manifoundation.core.robots.hand import Hand

HEAT_RADIUS = 0.015  # m: object points this close to a fingertip count as touched


@dataclass(frozen=True)
class InitCandidate:
    """A fitted initial pose: pose, ``assignment[h]`` = fingertip of contact h, its IoU and fit error (m)."""

    pose: HandPose
    assignment: tuple[int, ...]
    iou: float
    rms: float


@dataclass(frozen=True)
class RestGeometry:
    """Fingertips (m, 3), spheres (S, 3) and which spheres are on fingertips, in the palm frame at rest."""

    tips: np.ndarray
    spheres: np.ndarray
    tip_sphere: np.ndarray


def rest_geometry(hand: Hand) -> RestGeometry:
    """Palm-frame rest geometry (palm at the origin, identity orientation, joints at rest)."""
    pos = torch.zeros(1, 3, dtype=torch.float64)
    quat = torch.tensor([[1.0, 0.0, 0.0, 0.0]], dtype=torch.float64)
    q = torch.as_tensor(hand.rest, dtype=torch.float64)[None]
    with torch.no_grad():
        tips = hand.fingertips(pos, quat, q)[0].numpy()
        sph = hand.spheres(pos, quat, q, jacobian=False)[0][0].numpy()
    on_tip = np.asarray(hand.sphere_fingertip) >= 0
    return RestGeometry(tips, sph, on_tip)


def opposition(rest: RestGeometry) -> tuple[np.ndarray, np.ndarray]:
    """The hand's rest-pose opposition in its palm frame: thumb tip (3,) and mean of the other tips (3,).

    The thumb is the fingertip farthest from the mean of the others (for a two-finger gripper, the first).
    """
    tips = rest.tips
    thumb = int(np.argmax(_thumb_gaps(tips)))
    return tips[thumb], np.delete(tips, thumb, axis=0).mean(axis=0)


def distinct_opposition(rest: RestGeometry, margin: float = 1.02) -> bool:
    """Whether `opposition` is clear-cut: two fingertips, or a thumb whose gap to the mean of the other tips is at
    least ``margin`` times the next largest (leap: 1.04; not so for the barrett hand, whose two spread tips tie)."""
    if len(rest.tips) <= 2:
        return True
    gaps = np.sort(_thumb_gaps(rest.tips))
    return bool(gaps[-1] >= margin * gaps[-2])


def _thumb_gaps(tips: np.ndarray) -> np.ndarray:
    return np.array([np.linalg.norm(tips[i] - np.delete(tips, i, axis=0).mean(axis=0)) for i in range(len(tips))])


def heatmap(points: np.ndarray, sources: np.ndarray, radius: float = HEAT_RADIUS) -> np.ndarray:
    """(N,) bool: object points within ``radius`` of any source point."""
    d = np.linalg.norm(points[:, None, :] - sources[None, :, :], axis=2)
    return np.asarray(d.min(axis=1) < radius)


def iou(a: np.ndarray, b: np.ndarray) -> float:
    """Intersection over union of two boolean maps (0 when both are empty)."""
    union = np.logical_or(a, b).sum()
    return float(np.logical_and(a, b).sum() / union) if union else 0.0


def wahba(
    src_vecs: np.ndarray, dst_vecs: np.ndarray, weights: np.ndarray
) -> np.ndarray:
    """Rotation R minimising Σ w_k ‖R s_k − d_k‖² (SVD)."""
    h = (src_vecs * weights[:, None]).T @ dst_vecs
    u, _, vt = np.linalg.svd(h)
    d = np.sign(np.linalg.det(vt.T @ u.T)) or 1.0
    rot: np.ndarray = vt.T @ np.diag([1.0, 1.0, d]) @ u.T
    return rot


def approach_directions(contacts: np.ndarray, normals: np.ndarray) -> list[np.ndarray]:
    """Candidate world approach directions for the palm (see module doc)."""
    inward = -normals.sum(axis=0)
    if np.linalg.norm(inward) > 0.5 * len(normals) or len(contacts) == 1:
        return [inward / max(np.linalg.norm(inward), 1e-12)]
    centred = contacts - contacts.mean(axis=0)
    axis = np.linalg.svd(centred)[2][0]
    helper = np.array([1.0, 0, 0]) if abs(axis[0]) < 0.9 else np.array([0, 1.0, 0])
    e1 = np.cross(axis, helper)
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(axis, e1)
    return [np.cos(a) * e1 + np.sin(a) * e2 for a in np.linspace(0, 2 * np.pi, 6, endpoint=False)]


def fit_palm(
    rest_tips: np.ndarray,
    contacts: np.ndarray,
    approach_axis: np.ndarray,
    direction: np.ndarray,
    approach_weight: float,
) -> tuple[np.ndarray, np.ndarray, float]:
    """Palm rotation and position bringing ``rest_tips`` (H, 3, palm frame) onto ``contacts`` (H, 3).

    Returns (R, t, rms fingertip error).
    """
    mu_s, mu_d = rest_tips.mean(axis=0), contacts.mean(axis=0)
    src = np.vstack([rest_tips - mu_s, approach_axis[None]])
    dst = np.vstack([contacts - mu_d, direction[None]])
    spread = max(float(np.mean(np.sum((contacts - mu_d) ** 2, axis=1))), 1e-6)
    w = np.concatenate([np.ones(len(contacts)), [approach_weight * spread * max(1, 4 - len(contacts))]])
    rot = wahba(src, dst, w)
    t = mu_d - rot @ mu_s
    rms = float(np.sqrt(np.mean(np.sum((rest_tips @ rot.T + t - contacts) ** 2, axis=1))))
    return rot, t, rms


def fit_palms(
    rest_tips: np.ndarray, assigns: list[tuple[int, ...]], contacts: np.ndarray, approach_axis: np.ndarray,
    directions: np.ndarray, approach_weight: float,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:  # fmt: skip
    """`fit_palm` for every approach direction (d, 3) × assignment (A of them, H fingertips each), direction-major:
    rotations (d·A, 3, 3), positions (d·A, 3) and rms fingertip errors (d·A,), in one batched SVD."""
    tips = rest_tips[np.asarray(assigns, dtype=np.int64)]  # (A, H, 3)
    mu_s, mu_d = tips.mean(axis=1), contacts.mean(axis=0)
    spread = max(float(np.mean(np.sum((contacts - mu_d) ** 2, axis=1))), 1e-6)
    w = np.concatenate([np.ones(len(contacts)), [approach_weight * spread * max(1, 4 - len(contacts))]])
    n_dir, n_as = len(directions), len(assigns)
    src = np.concatenate([tips - mu_s[:, None], np.broadcast_to(approach_axis, (n_as, 1, 3))], axis=1)  # (A, H+1, 3)
    src = np.broadcast_to(src[None], (n_dir, *src.shape)).reshape(n_dir * n_as, -1, 3)
    dst = np.concatenate([np.broadcast_to(contacts - mu_d, (n_dir, *contacts.shape)), directions[:, None]], axis=1)
    dst = np.repeat(dst, n_as, axis=0)  # (d·A, H+1, 3)
    hmat = np.matmul(np.swapaxes(src * w[None, :, None], 1, 2), dst)
    u, _, vt = np.linalg.svd(hmat)
    v, ut = np.swapaxes(vt, 1, 2), np.swapaxes(u, 1, 2)
    sign = np.sign(np.linalg.det(v @ ut))
    sign[sign == 0] = 1.0
    fix = np.tile(np.eye(3), (len(hmat), 1, 1))
    fix[:, 2, 2] = sign
    rots = v @ fix @ ut
    mu_all = np.tile(mu_s, (n_dir, 1))
    ts = mu_d - np.einsum("fab,fb->fa", rots, mu_all)
    tips_all = np.tile(tips, (n_dir, 1, 1))
    placed = np.einsum("fab,fkb->fka", rots, tips_all) + ts[:, None]
    rms = np.sqrt(np.mean(np.sum((placed - contacts[None]) ** 2, axis=2), axis=1))
    return rots, ts, rms


def back_off(
    rot: np.ndarray, t: np.ndarray, rest: RestGeometry, radii: np.ndarray, field: PointCloudField,
    direction: np.ndarray, max_distance: float = 0.1, step: float = 0.005,
) -> np.ndarray:
    """Move the palm along −direction until no non-fingertip sphere penetrates (at most ``max_distance``)."""
    body = ~rest.tip_sphere
    if not body.any():
        return t
    centres = rest.spheres[body] @ rot.T + t
    r = radii[body]
    blocking = np.zeros(0, dtype=np.int64)  # the spheres that penetrated at the last shift
    for k in range(int(max_distance / step) + 1):
        shift = -direction * step * k
        # the spheres that penetrated last time are measured first: while one of them still does, the others
        # need not be (Φ of each point is independent of the others: the same shift is found)
        if len(blocking):
            phi = field.signed_distance(centres[blocking] + shift)[0]
            if np.any(phi < r[blocking]):
                blocking = blocking[phi < r[blocking]]
                continue
        others = np.setdiff1d(np.arange(len(centres)), blocking, assume_unique=True)
        phi = field.signed_distance(centres[others] + shift)[0]
        if np.all(phi >= r[others]):
            return t + shift
        blocking = others[phi < r[others]]
    return t - direction * max_distance


def touch_overlap(field: PointCloudField, tips: np.ndarray, target: np.ndarray, radius: float
                  ) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """For each fit's fingertips (F, m, 3): how many of the points they touch (within ``radius``) lie in the
    boolean map ``target`` (N,), and how many lie in either — the intersection (F,) and union (F,) of the IoU.

    Where a fit's fingertips are more than 2 ``radius`` apart their balls are disjoint, so the counts are sums of
    per-fingertip ball counts (on the cloud and on the target's points); other fits take the points' indices.
    """
    f, m = tips.shape[:2]
    flat = tips.reshape(-1, 3)
    touched = field.ball_counts(flat, radius).reshape(f, m).sum(axis=1)
    goal = field.points[target]
    inter = np.zeros(f, dtype=np.int64)
    if len(goal):
        inter = cKDTree(goal).query_ball_point(flat, radius, return_length=True).reshape(f, m).sum(axis=1)
    gap = np.linalg.norm(tips[:, :, None] - tips[:, None], axis=-1) + np.where(np.eye(m, dtype=bool), np.inf, 0.0)
    for k in np.flatnonzero(gap.min(axis=(1, 2)) <= 2.0 * radius):  # balls may overlap: count each point once
        seen = np.zeros(len(field.points), dtype=bool)
        for ball in field.ball_indices(tips[k], radius):
            seen[ball] = True
        touched[k], inter[k] = seen.sum(), (seen & target).sum()
    return inter, touched + int(target.sum()) - inter


def initialise(
    hand: Hand,
    field: PointCloudField,
    contacts: np.ndarray,
    contact_normals: np.ndarray,
    predicted: np.ndarray | None = None,
    top_k: int = 1,
    approach_weight: float = 0.5,
    radius: float = HEAT_RADIUS,
    rest: RestGeometry | None = None,
) -> list[InitCandidate]:
    """Best initial poses for contacts (paper §III-B-1).

    Args:
        hand: a `manifoundation.core.robots.Hand`.
        field: the object's point field (its points carry the heatmaps).
        contacts: (H, 3) contact points, H ≤ number of fingertips. contact_normals: (H, 3) outward normals.
        predicted: (N,) predicted heatmap in [0, 1] on ``field.points``; None: the heatmap of ``contacts``.
        top_k: how many candidates to return (best first).
        approach_weight: weight of the approach-direction pair relative to the fingertip pairs.
        radius: heatmap radius (m).
        rest: precomputed `rest_geometry(hand)`.

    Returns:
        Up to ``top_k`` candidates, best first.

    Raises:
        ValueError: no contacts, or more contacts than fingertips.
    """
    contacts = np.asarray(contacts, dtype=np.float64).reshape(-1, 3)
    m, h = hand.num_fingertips, len(contacts)
    if h == 0 or h > m:
        raise ValueError(f"need 1..{m} contacts for {m} fingertips, got {h}")
    rest = rest or rest_geometry(hand)
    target = heatmap(field.points, contacts, radius) if predicted is None else np.asarray(predicted) >= 0.5
    radii = np.asarray(hand.sphere_radii, dtype=np.float64)
    axis = np.asarray(hand.approach_axis, dtype=np.float64)
    directions = approach_directions(contacts, contact_normals)
    assigns = list(itertools.permutations(range(m), h))
    rots, ts, rms = fit_palms(rest.tips, assigns, contacts, axis, np.asarray(directions), approach_weight)
    fits = [(rots[f], ts[f], float(rms[f]), assigns[f % len(assigns)]) for f in range(len(rots))]
    # score on the fitted (not yet backed-off) pose: where the fingertips land
    inter, union = touch_overlap(field, np.einsum("fab,kb->fka", rots, rest.tips) + ts[:, None], target, radius)
    scored = []
    for f, (rot, t, err, assign) in enumerate(fits):
        score = int(inter[f]) / int(union[f]) if union[f] else 0.0
        scored.append((score, -err, rot, t, assign, None))
    scored.sort(key=lambda s: (s[0], s[1]), reverse=True)
    out = []
    for score, neg_rms, rot, t, assign, _ in scored[:top_k]:
        t = back_off(rot, t, rest, radii, field, rot @ axis)
        quat = Rotation.from_matrix(rot).as_quat()[[3, 0, 1, 2]]
        pose = HandPose(t, quat, np.asarray(hand.rest, dtype=np.float64).copy())
        out.append(InitCandidate(pose, tuple(int(a) for a in assign), float(score), float(-neg_rms)))
    return out
