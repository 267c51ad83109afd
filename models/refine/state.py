"""Hand configuration, the object's distance field protocol, and the local model at one iterate."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np
import torch

from models.refine.forces import ForceSolution, solve_forces
from models.refine.wrench import WrenchTask


class DistanceField(Protocol):
    """What refinement needs from the object (`models.geometry.ObjectGeometry` satisfies it)."""

    def signed_distance(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(M, 3) → Φ (M,), ∇Φ (M, 3) (outward unit normal at the nearest point), nearest point (M, 3)."""
        ...


@dataclass(frozen=True)
class HandPose:
    """Floating palm pose and finger joints (numpy, float64)."""

    palm_pos: np.ndarray  # (3,)
    palm_quat: np.ndarray  # (4,) wxyz
    q: np.ndarray  # (D,)

    def tensors(self) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
        """Batch-of-one float64 tensors for the `Hand` API."""
        return (
            torch.as_tensor(self.palm_pos, dtype=torch.float64)[None],
            torch.as_tensor(self.palm_quat, dtype=torch.float64)[None],
            torch.as_tensor(self.q, dtype=torch.float64)[None],
        )

    def step(self, hand: Any, delta: np.ndarray) -> HandPose:
        """Apply δ (6 + D) with the hand's exponential map (palm rotation in the world frame)."""
        pos, quat, q = hand.apply_delta(*self.tensors(), torch.as_tensor(delta, dtype=torch.float64)[None])
        return HandPose(pos[0].numpy().copy(), quat[0].numpy().copy(), q[0].numpy().copy())


@dataclass
class Linearisation:
    """Everything the SCP step needs at one iterate (all numpy, float64).

    Attributes:
        tips, tip_jac: (m, 3), (m, 3, n) fingertip points and Jacobians (n = 6 + D).
        tip_phi, tip_grad: (m,), (m, 3) distance the objective drives to zero (Φ, or Φ^R with a mask) and its
            gradient.
        normals: (m, 3) outward normal at each tip's projection on the surface (grasp maps, friction cones).
        normal_jac: (m, 3, 3) ∂n/∂p at the tips (zeros when the field has no curvature model).
        forces: f* (m, 3) and the inner solution.
        sph, sph_jac, sph_phi, sph_grad, sph_radius, sph_allow: spheres and Φ at their centres; ``sph_allow``
            is the allowed overlap (m) per sphere (fingertip spheres may touch).
        pair_idx, pair_dist, pair_dir: self-collision pairs (P, 2), their centre distances and unit directions.
        q, lower, upper: joint values and limits (D,).
        region_point: with a region mask, each contact point's distance to the nearest allowed sample (m,) — the
            verification's region test, which the convergence test also applies (Φ^R is to the samples' discs).
    """

    task: WrenchTask
    mu: float
    max_normal_force: float
    tips: np.ndarray
    tip_jac: np.ndarray
    tip_phi: np.ndarray
    tip_grad: np.ndarray
    normals: np.ndarray
    normal_jac: np.ndarray
    solution: ForceSolution
    sph: np.ndarray
    sph_jac: np.ndarray
    sph_phi: np.ndarray
    sph_grad: np.ndarray
    sph_radius: np.ndarray
    sph_allow: np.ndarray
    pair_idx: np.ndarray
    pair_dist: np.ndarray
    pair_dir: np.ndarray
    q: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    region_point: np.ndarray | None = None

    @property
    def forces(self) -> np.ndarray:
        return self.solution.forces

    @property
    def residual_norm(self) -> float:
        return self.solution.residual_norm

    def penetration(self) -> np.ndarray:
        """Per-sphere penetration beyond the allowance (≥ 0)."""
        return np.maximum(0.0, self.sph_radius - self.sph_allow - self.sph_phi)

    def self_overlap(self) -> np.ndarray:
        """Per-pair overlap of self-collision spheres (≥ 0)."""
        if not len(self.pair_idx):
            return np.zeros(0)
        r = self.sph_radius[self.pair_idx].sum(axis=1)
        return np.maximum(0.0, r - self.pair_dist)


def sphere_allowance(hand: Any, tip_allowance: float) -> np.ndarray:
    """Per-sphere overlap (m) the non-penetration rows allow: ``tip_allowance`` for spheres on fingertip links
    (they carry the contacts), none for the others. Verification checks the real meshes."""
    owner = np.asarray(getattr(hand, "sphere_fingertip", np.full(len(hand.sphere_radii), -1)))
    return np.where(owner >= 0, tip_allowance, 0.0)


PAD_TOLERANCE = 3e-3  # m: spheres this much farther from the tip point than the nearest one also form the pad
_CONTACT: dict[int, tuple[np.ndarray, np.ndarray, list[np.ndarray], np.ndarray]] = {}


def _contact_model(hand: Any) -> tuple[np.ndarray, np.ndarray, list[np.ndarray], np.ndarray]:
    key = id(hand)
    if key not in _CONTACT:
        pos = torch.zeros(1, 3, dtype=torch.float64)
        quat = torch.tensor([[1.0, 0.0, 0.0, 0.0]], dtype=torch.float64)
        q = torch.as_tensor(hand.rest, dtype=torch.float64)[None]
        with torch.no_grad():
            tips = hand.fingertips(pos, quat, q)[0].numpy()
            sph = hand.spheres(pos, quat, q, jacobian=False)[0][0].numpy()
        radius = np.asarray(hand.sphere_radii, dtype=np.float64)
        owner = np.asarray(getattr(hand, "sphere_fingertip", np.full(len(radius), -1)))
        idx = np.full(len(tips), -1)
        pads: list[np.ndarray] = []
        for i in range(len(tips)):
            mine = np.flatnonzero(owner == i)
            if not len(mine):
                pads.append(np.zeros(0, dtype=np.int64))
                continue
            dist = np.linalg.norm(sph[mine] - tips[i], axis=1)
            idx[i] = mine[np.argmin(dist)]
            pads.append(mine[dist <= dist.min() + PAD_TOLERANCE])
        every = np.unique(np.concatenate([np.zeros(0, dtype=np.int64), *pads]))
        _CONTACT[key] = (idx, np.where(idx >= 0, radius[np.maximum(idx, 0)], 0.0), pads, every)
    return _CONTACT[key]


def contact_spheres(hand: Any) -> tuple[np.ndarray, np.ndarray]:
    """Per fingertip: the index of its primary pad sphere (the sphere on its link nearest to its tip point; −1 if
    none) and that sphere's radius (0 for −1). Data generation's IK drives this sphere onto the surface.

    The fingertip is modelled by its pad: its contact point is the pad sphere point nearest to the object,
    ``p = c − r ∇Φ(c)``, at distance ``Φ(c) − r``. The hand's fixed tip point lies inside the fitted spheres
    (Allegro/LEAP: 3-4 mm inside two overlapping ones), so with a fixed point the fingertip can touch only in
    one orientation and the SCP stalled 6-20 mm off the surface in our runs; the pad model is orientation-free
    and consistent with the non-penetration rows. See `pad_spheres` for pads made of several spheres.
    """
    idx, rad, _, _ = _contact_model(hand)
    return idx, rad


def pad_spheres(hand: Any) -> list[np.ndarray]:
    """Per fingertip, the indices of its pad spheres: those on its link whose centre (at rest) is at most
    ``PAD_TOLERANCE`` farther from the tip point than the primary pad sphere's (empty: no sphere, the tip point).

    The sphere fit may split a fingertip's end into several spheres about equally near the tip point (LEAP: two
    side by side, 11.5 and 12.5 mm from it); the one nearest the object is the contact. With the primary sphere
    alone, a LEAP finger touching with its other half stalled 6 mm "off" the surface (refinement evaluation,
    blob-13c08faf).
    """
    return _contact_model(hand)[2]


def pad_candidates(hand: Any) -> np.ndarray:
    """The indices of every fingertip's pad spheres, sorted, without repeats (the spheres to measure)."""
    return _contact_model(hand)[3]


def select_pads(hand: Any, gap: np.ndarray) -> np.ndarray:
    """Per fingertip, the pad sphere (index into all spheres) nearest to touching: smallest |``gap``| (S,) (its
    Φ − r); −1 for fingertips without spheres. Not the most negative gap: the spheres over-approximate the link,
    so one pad sphere may overlap the object by several mm (sampled LEAP grasps: 6.9 mm, no mesh penetration)
    while its neighbour touches."""
    out = np.full(len(pad_spheres(hand)), -1, dtype=np.int64)
    for i, pad in enumerate(pad_spheres(hand)):
        if len(pad):
            out[i] = pad[np.argmin(np.abs(gap[pad]))]
    return out


def contact_points(
    hand: Any, field: DistanceField, tips: np.ndarray, tip_jac: np.ndarray | None, sph: np.ndarray,
    sph_jac: np.ndarray | None, tip_field: Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]] | None = None,
) -> tuple[np.ndarray, np.ndarray | None, np.ndarray, np.ndarray]:
    """Fingertip contact points (m, 3), their Jacobians, distances Φ(c) − r (m,) and gradients (m, 3), each on the
    fingertip's pad sphere nearest to the object (`pad_spheres`) — or, with ``tip_field`` (a region's Φ^R), the
    pad sphere whose contact point is nearest to the region: the tip objective is then the minimum over the pad
    spheres of a continuous function, so it stays continuous when the choice switches (choosing by Φ made a LEAP
    finger's Φ^R jump by 3 mm between its two touching pad spheres, and the trust region collapsed)."""
    radius = np.asarray(hand.sphere_radii, dtype=np.float64)
    candidates = pad_candidates(hand)
    score = np.full(len(radius), np.inf)
    phi_s, grad_s, normal_s = np.zeros(len(radius)), np.zeros((len(radius), 3)), np.zeros((len(radius), 3))
    if len(candidates):
        c = sph[candidates]
        phi_s[candidates], grad_s[candidates], _ = field.signed_distance(c)
        normal_s[candidates] = _contact_normal(field, c, grad_s[candidates])
        below = c - radius[candidates, None] * normal_s[candidates]  # each candidate's contact point
        score[candidates] = phi_s[candidates] - radius[candidates] if tip_field is None else tip_field(below)[0]
    idx = select_pads(hand, score)
    padded, sel = idx >= 0, idx[idx >= 0]
    points = np.array(tips, dtype=np.float64)  # fingertips without spheres: the tip point itself
    phi, grad = np.zeros(len(tips)), np.zeros((len(tips), 3))
    points[padded] = sph[sel] - radius[sel, None] * normal_s[sel]
    phi[padded], grad[padded] = phi_s[sel] - radius[sel], grad_s[sel]
    if not padded.all():
        phi[~padded], grad[~padded], _ = field.signed_distance(points[~padded])
    jac = None
    if tip_jac is not None and sph_jac is not None:
        jac = np.where(padded[:, None, None], sph_jac[np.maximum(idx, 0)], tip_jac)
    return points, jac, phi, grad


def _contact_normal(field: DistanceField, centres: np.ndarray, grad: np.ndarray) -> np.ndarray:
    """The direction from a pad centre to its contact point (reversed): the smoothed surface normal where the field
    has one — the nearest sample's normal is piecewise constant, so the point jumped by r·Δn between samples."""
    surface_normal = getattr(field, "surface_normal", None)
    return np.asarray(surface_normal(centres)) if surface_normal is not None else grad


def linearise(
    hand: Any,
    pose: HandPose,
    field: DistanceField,
    task: WrenchTask,
    mu: float,
    max_normal_force: float,
    tip_field: Any | None = None,
    tip_sphere_allowance: float = 1e-3,
) -> Linearisation:
    """Kinematics, distances and optimal forces at ``pose``.

    Args:
        hand: a `models.robots.Hand`.
        pose: the iterate.
        field: object signed distance (penetration, normals).
        task: residual definition.
        mu, max_normal_force: friction and force bound.
        tip_field: optional callable ``x -> (Φ^R, ∇Φ^R)`` used instead of Φ for the tip objective (masks).
        tip_sphere_allowance: overlap allowed for spheres on fingertip links (they carry the contacts).
    """
    pos, quat, q = pose.tensors()
    with torch.no_grad():
        tips_t, tip_jac_t = hand.fingertip_jacobians(pos, quat, q)
        sph_t, sph_jac_t = hand.spheres(pos, quat, q)
    sph, sph_jac = sph_t[0].numpy(), sph_jac_t[0].numpy()
    tips, tip_jac, tip_phi, tip_grad = contact_points(
        hand, field, tips_t[0].numpy(), tip_jac_t[0].numpy(), sph, sph_jac, tip_field
    )
    assert tip_jac is not None
    phi_all, grad_all, _ = field.signed_distance(np.concatenate([tips, sph]))
    m = len(tips)
    normals = field.surface_normal(tips) if hasattr(field, "surface_normal") else tip_grad
    normal_jac = (
        field.normal_jacobian(tips) if hasattr(field, "normal_jacobian") else np.zeros((len(tips), 3, 3))
    )
    if tip_field is not None:
        tip_phi, tip_grad = tip_field(tips)
    point_distance = getattr(field, "region_point_distance", None) if tip_field is not None else None
    solution = solve_forces(task, tips, normals, mu, max_normal_force)
    radius = np.asarray(hand.sphere_radii, dtype=np.float64)
    pairs = np.asarray(hand.self_collision_pairs, dtype=np.int64).reshape(-1, 2)
    diff = sph[pairs[:, 0]] - sph[pairs[:, 1]] if len(pairs) else np.zeros((0, 3))
    dist = np.linalg.norm(diff, axis=1)
    return Linearisation(
        task=task,
        mu=mu,
        max_normal_force=max_normal_force,
        tips=tips,
        tip_jac=tip_jac,
        tip_phi=np.asarray(tip_phi, dtype=np.float64),
        tip_grad=np.asarray(tip_grad, dtype=np.float64),
        normals=np.asarray(normals, dtype=np.float64),
        normal_jac=normal_jac,
        solution=solution,
        sph=sph,
        sph_jac=sph_jac,
        sph_phi=np.asarray(phi_all[m:], dtype=np.float64),
        sph_grad=np.asarray(grad_all[m:], dtype=np.float64),
        sph_radius=radius,
        sph_allow=sphere_allowance(hand, tip_sphere_allowance),
        pair_idx=pairs,
        pair_dist=dist,
        pair_dir=diff / np.maximum(dist, 1e-12)[:, None],
        q=pose.q,
        lower=np.asarray(hand.lower, dtype=np.float64),
        upper=np.asarray(hand.upper, dtype=np.float64),
        region_point=None if point_distance is None else np.asarray(point_distance(tips), dtype=np.float64),
    )
