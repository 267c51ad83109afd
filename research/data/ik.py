"""Batched damped-least-squares IK of fingertips onto surface points (palm fixed, or free for coupled hands).

Rows of a batch are independent problems. Phase 1 drives each fingertip towards its sampled target; phase 2
projects the tips onto the surface (target = the nearest surface point, i.e. Newton on Φ(p) = 0). Fingers
whose joints are disjoint are solved in the same row without interacting (the damped normal matrix is block
diagonal), which is what makes the per-finger solutions combinable afterwards.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING

import numpy as np
import torch

if TYPE_CHECKING:
    from manifoundation.core.robots.hand import Hand

DAMPING = 0.02  # λ (m) of δ = Jᵀ (J Jᵀ + λ² I)⁻¹ e
MAX_JOINT_STEP = 0.25  # rad (or m) per iteration
MAX_PALM_STEP = 0.01  # m / rad per iteration when the palm is free


def finger_joint_sets(hand: Hand) -> list[np.ndarray]:
    """For each fingertip, the indices (into q) of the joints that move it (at the rest pose)."""
    pos = torch.zeros(1, 3, dtype=torch.float64)
    quat = torch.tensor([[1.0, 0.0, 0.0, 0.0]], dtype=torch.float64)
    q = torch.as_tensor(hand.rest[None], dtype=torch.float64)
    _, jac = hand.fingertip_jacobians(pos, quat, q)
    cols = jac[0, :, :, 6:].abs().sum(dim=1) > 1e-9  # (m, D)
    # a joint at a singular configuration can show a zero column: also use the limits' midpoint
    q2 = torch.as_tensor(((hand.lower + hand.upper) / 2)[None], dtype=torch.float64)
    _, jac2 = hand.fingertip_jacobians(pos, quat, q2)
    cols = cols | (jac2[0, :, :, 6:].abs().sum(dim=1) > 1e-9)
    return [np.flatnonzero(c.numpy()) for c in cols]


def finger_groups(joint_sets: list[np.ndarray]) -> list[list[int]]:
    """Fingers grouped by shared joints (connected components)."""
    m = len(joint_sets)
    parent = list(range(m))

    def find(i: int) -> int:
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    for i in range(m):
        for j in range(i + 1, m):
            if np.intersect1d(joint_sets[i], joint_sets[j]).size:
                parent[find(i)] = find(j)
    groups: dict[int, list[int]] = {}
    for i in range(m):
        groups.setdefault(find(i), []).append(i)
    return list(groups.values())


TIP_WEIGHT = 0.3  # weight of the contact point's rows; the pad-centre rows have weight 1


def tip_points(hand: Hand) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Bodies (m,), contact points (m, 3) and pad centres (m, 3) in their body frames, and the pad radii (m,).

    The pad of a fingertip is the sphere that best fits its real surface near the tip point (`fit_pad`, on the
    samples of `manifoundation.core.robots.pads`, the contact model refinement and verification use): driving its centre
    to ``target + radius · n`` puts the real fingertip surface on the target whatever the finger's orientation. Flat
    pads use the sphere tangent to them at the tip (`fit_pad`).
    """
    bodies, tips, pads, radii = [], [], [], []
    for i, link in enumerate(hand.fingertip_links):
        b, T = hand.tree.link_body[link]
        tip = T[:3, :3] @ hand.tip_offsets[i] + T[:3, 3]
        centre, radius = fit_pad(hand, i, tip)
        bodies.append(b)
        tips.append(tip)
        pads.append(centre)
        radii.append(radius)
    return np.asarray(bodies, dtype=np.int64), np.asarray(tips), np.asarray(pads), np.asarray(radii, dtype=float)


PAD_FIT_RADIUS = 0.01
"""m: pad samples this close to the sample nearest the tip point define the fitted pad sphere."""
PAD_FIT_MAX_RADIUS = 0.03
PAD_FIT_MAX_RMS = 1e-3
PAD_FLAT_RADIUS = 0.01
CONTACT_STANDOFF = 1.5e-3
"""m: the pads are driven this far outside the surface: the fitted pad sphere is not the real surface (a flat pad
tilted by a few degrees dips its edge into the object), and the verification's contact tolerance is 5 mm."""
"""m: a flat pad is modelled by the sphere of this radius tangent to it at the sample nearest the tip point."""


def fit_pad(hand: Hand, fingertip: int, tip: np.ndarray) -> tuple[np.ndarray, float]:
    """The sphere (centre (3,) body frame, radius) fitted (algebraic least squares) to fingertip ``fingertip``'s
    surface samples within ``PAD_FIT_RADIUS`` of the sample nearest its tip point. Where the surface there is flat
    (radius > ``PAD_FIT_MAX_RADIUS``) or no sphere fits (rms > ``PAD_FIT_MAX_RMS``): the sphere of radius
    ``PAD_FLAT_RADIUS`` tangent to the surface at the sample nearest the tip point."""
    surf = hand.contact_surface
    mine = np.flatnonzero(surf.fingertip == fingertip)
    pts = surf.local[mine]
    anchor = pts[np.argmin(np.linalg.norm(pts - tip, axis=1))]
    near = pts[np.linalg.norm(pts - anchor, axis=1) <= PAD_FIT_RADIUS]
    if len(near) >= 8:
        A = np.hstack([2 * near, np.ones((len(near), 1))])
        sol, *_ = np.linalg.lstsq(A, (near**2).sum(axis=1), rcond=None)
        centre = sol[:3]
        radius = float(np.sqrt(max(sol[3] + centre @ centre, 0.0)))
        rms = float(np.sqrt(np.mean((np.linalg.norm(near - centre, axis=1) - radius) ** 2)))
        if radius <= PAD_FIT_MAX_RADIUS and rms <= PAD_FIT_MAX_RMS:
            return centre, radius
    normal = surf.normals[mine][np.argmin(np.linalg.norm(pts - tip, axis=1))]
    return anchor - PAD_FLAT_RADIUS * normal, PAD_FLAT_RADIUS


def pad_spheres(
    hand: Hand,
    palm_pos: torch.Tensor,
    palm_quat: torch.Tensor,
    q: torch.Tensor,
) -> tuple[np.ndarray, np.ndarray]:
    """World pad centres (B, m, 3) and radii (m,)."""
    bodies, _, pad_local, radii = tip_points(hand)
    T = hand.tree.body_poses(palm_pos, palm_quat, q)
    Tb = T[:, torch.as_tensor(bodies)]
    local = torch.as_tensor(pad_local, dtype=q.dtype)
    return ((Tb[..., :3, :3] @ local[..., None])[..., 0] + Tb[..., :3, 3]).numpy(), radii


def _points_and_jacobian(
    hand: Hand,
    palm_pos: torch.Tensor,
    palm_quat: torch.Tensor,
    q: torch.Tensor,
    bodies: np.ndarray,
    local: torch.Tensor,
) -> tuple[torch.Tensor, torch.Tensor]:
    T = hand.tree.body_poses(palm_pos, palm_quat, q)
    Tb = T[:, torch.as_tensor(bodies)]
    pts = (Tb[..., :3, :3] @ local[..., None])[..., 0] + Tb[..., :3, 3]
    return pts, hand.tree.point_jacobian(T, bodies, pts, palm_pos)


def solve_ik(
    hand: Hand,
    palm_pos: torch.Tensor,
    palm_quat: torch.Tensor,
    q: torch.Tensor,
    targets: torch.Tensor,
    surface: Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]],
    *,
    free_palm: bool = False,
    iters_target: int = 15,
    iters_project: int = 10,
) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor, torch.Tensor]:
    """Move fingertips onto the surface near ``targets``, pads facing the surface.

    Each fingertip contributes its pad centre (→ the target pushed out along the surface normal by the pad
    radius, see `tip_points`) and, with weight ``TIP_WEIGHT``, its contact point (→ the target).

    Args:
        hand: a `manifoundation.core.robots.Hand`.
        palm_pos, palm_quat, q: (B, 3), (B, 4), (B, D) float64 start.
        targets: (B, m, 3) per-fingertip targets.
        surface: (M, 3) → nearest surface points (M, 3) and their outward normals (M, 3).
        free_palm: also move the palm (hands whose fingers share joints).
        iters_target, iters_project: iterations of each phase.

    Returns:
        palm_pos, palm_quat, q, tips (B, m, 3) at the end.
    """
    lower = torch.as_tensor(hand.lower, dtype=q.dtype)
    upper = torch.as_tensor(hand.upper, dtype=q.dtype)
    B, m = targets.shape[:2]
    D = q.shape[1]
    bodies, tip_local, pad_local, radii = tip_points(hand)
    local = torch.as_tensor(np.concatenate([tip_local, pad_local]), dtype=q.dtype)
    bodies2 = np.concatenate([bodies, bodies])
    weights = torch.cat([torch.full((3 * m,), TIP_WEIGHT, dtype=q.dtype), torch.ones(3 * m, dtype=q.dtype)])
    depth = torch.as_tensor(radii + CONTACT_STANDOFF, dtype=q.dtype)[None, :, None]
    _, tgt_normals = surface(targets.reshape(-1, 3).numpy())
    tgt_normals_t = torch.as_tensor(tgt_normals, dtype=q.dtype).reshape(B, m, 3)
    for it in range(iters_target + iters_project):
        pts, jac = _points_and_jacobian(hand, palm_pos, palm_quat, q, bodies2, local)
        tips = pts[:, :m]
        if it >= iters_target:
            # project the pad centre: its nearest surface point is where the pad touches
            near, nrm = surface(pts[:, m:].reshape(-1, 3).numpy())
            goal = torch.as_tensor(near, dtype=q.dtype).reshape(B, m, 3)
            normal = torch.as_tensor(nrm, dtype=q.dtype).reshape(B, m, 3)
        else:
            goal, normal = targets, tgt_normals_t
        goal2 = torch.cat([goal, goal + depth * normal], dim=1)
        err = (goal2 - pts).reshape(B, 6 * m) * weights
        J = jac.reshape(B, 6 * m, 6 + D) * weights[:, None]
        if not free_palm:
            J = J[:, :, 6:]
        n = J.shape[2]
        A = J.transpose(1, 2) @ J + DAMPING**2 * torch.eye(n, dtype=q.dtype)
        delta = torch.linalg.solve(A, J.transpose(1, 2) @ err[..., None])[..., 0]
        if free_palm:
            palm = delta[:, :6].clamp(-MAX_PALM_STEP * 3, MAX_PALM_STEP * 3)
            dq = delta[:, 6:].clamp(-MAX_JOINT_STEP, MAX_JOINT_STEP)
            palm_pos, palm_quat, _ = hand.apply_delta(palm_pos, palm_quat, q, torch.cat([palm, dq], dim=1))
        else:
            dq = delta.clamp(-MAX_JOINT_STEP, MAX_JOINT_STEP)
        q = torch.minimum(torch.maximum(q + dq, lower), upper)
    tips = hand.fingertips(palm_pos, palm_quat, q)
    return palm_pos, palm_quat, q, tips


def separate(
    hand: Hand,
    palm_pos: torch.Tensor,
    palm_quat: torch.Tensor,
    q: torch.Tensor,
    surface: Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]],
    iters: int = 8,
    margin: float = 2e-3,
) -> torch.Tensor:
    """Push overlapping self-collision sphere pairs apart while keeping the pads on the surface.

    Each iteration stacks the pad-centre rows (target: nearest surface point + radius · normal) and, for every
    pair overlapping within ``margin``, one row ``u·(J_a − J_b) δq = overlap + margin``; solved by damped least
    squares over the finger joints (palm fixed). Returns the new q (B, D).
    """
    pairs = torch.as_tensor(np.asarray(hand.self_collision_pairs, dtype=np.int64).reshape(-1, 2))
    if not len(pairs):
        return q
    radii = torch.as_tensor(hand.sphere_radii, dtype=q.dtype)
    need = radii[pairs].sum(dim=1) + margin
    lower = torch.as_tensor(hand.lower, dtype=q.dtype)
    upper = torch.as_tensor(hand.upper, dtype=q.dtype)
    B, m = q.shape[0], hand.num_fingertips
    bodies, _, pad_np, radii_np = tip_points(hand)
    pad_local = torch.as_tensor(pad_np, dtype=q.dtype)
    for _ in range(iters):
        c, jc = hand.spheres(palm_pos, palm_quat, q)
        diff = c[:, pairs[:, 0]] - c[:, pairs[:, 1]]
        dist = diff.norm(dim=-1)
        over = need[None] - dist  # (B, P)
        if not bool((over > 0).any()):
            break
        pads, jt = _points_and_jacobian(hand, palm_pos, palm_quat, q, bodies, pad_local)
        near, nrm = surface(pads.reshape(-1, 3).numpy())
        goal = torch.as_tensor(near + np.tile(radii_np + CONTACT_STANDOFF, B)[:, None] * nrm, dtype=q.dtype)
        goal = goal.reshape(B, m, 3)
        rows_t = jt[..., 6:].reshape(B, 3 * m, -1)
        err_t = (goal - pads).reshape(B, 3 * m)
        # least squares via the normal equations in joint space (few joints, many rows); a pair's row is zero
        # unless the pair overlaps, so only the overlapping pairs' rows are formed: every pair's, (B, P, 3, D)
        # with Allegro's 2 756 pairs, was most of data generation's time and memory
        A = rows_t.transpose(1, 2) @ rows_t + DAMPING**2 * torch.eye(rows_t.shape[2], dtype=q.dtype)
        rhs = (rows_t.transpose(1, 2) @ err_t[..., None])[..., 0]
        bi, pi = torch.nonzero(over > 0, as_tuple=True)
        u = diff[bi, pi] / dist[bi, pi, None].clamp_min(1e-9)
        jp = (u[..., None] * (jc[bi, pairs[pi, 0], :, 6:] - jc[bi, pairs[pi, 1], :, 6:])).sum(dim=1)  # (K, D)
        A.index_add_(0, bi, jp[:, :, None] * jp[:, None, :])
        rhs.index_add_(0, bi, jp * over[bi, pi, None])
        dq = torch.linalg.solve(A, rhs[..., None])[..., 0].clamp(-MAX_JOINT_STEP, MAX_JOINT_STEP)
        q = torch.minimum(torch.maximum(q + dq, lower), upper)
    return q
