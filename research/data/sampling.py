"""Hierarchical grasp sampling (paper appendix "Articulated/Rigid Bodies").

1. Palm poses facing the object: a surface point p and its normal n; the palm's approach axis points along −n
   (tilted up to ``MAX_TILT``), random roll, and the rest-pose fingertip centroid placed at p + δ n with δ from
   slightly outside down to inside the object (so the fingers can wrap around small objects).
2. Per-finger IK: each finger gets ``candidates`` surface targets near its rest fingertip (facing it); one
   batched damped-least-squares solve handles all (palm, candidate) rows, then projects the tips on the surface
   (`ik.py`). Hands whose fingers all share joints (parallel grippers) move the palm too.
3. Combine finger solutions: for each palm pose, random combinations of one converged solution per finger
   group.
4. Separate: a few least-squares steps push overlapping self-collision spheres apart while keeping the tips
   on the surface (`ik.separate`).
5. Reject with the verification's own tests: a pad sphere off the surface (|Φ(c) − r| > ``TIP_TOL``, exact
   mesh distance), two contacts closer than ``MIN_CONTACT_GAP``, hand–object penetration or self-collision
   deeper than 1 mm on the collision meshes (`manifoundation.core.geometry`, fcl), after fast pre-filters (`checks.py`).

Why one module: the three sampling levels share one set of per-object arrays and constants; split, each part would
re-derive them.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import torch
import trimesh
from scipy.spatial.transform import Rotation

from research.data.checks import PENETRATION_TOL, ObjectField, penetration_depth, self_overlap
from research.data.ik import finger_groups, finger_joint_sets, pad_spheres, separate, solve_ik
from research.data.pinch import sample_pinch_palms

if TYPE_CHECKING:
    from manifoundation.core.robots.hand import Hand

MAX_TILT = np.deg2rad(25.0)
TIP_TOL = 4e-3  # m, pad sphere to surface, |Φ(c) − r| (DESIGN §5 allows 5 mm)
PREFILTER_TOL = 3e-3  # m, fast point-cloud penetration pre-filter before the exact (fcl) test
MIN_CONTACT_GAP = 0.01  # m
CANDIDATE_RADIUS = 0.035  # m around the rest fingertip
VORONOI_MARGIN = 0.01  # m
PAD_FACING = 0.6  # a fingertip's pad direction must point into the surface: cos < −PAD_FACING
CLOSURE_MIN_EPSILON = 0.01  # closure sampling: ε margin, so that the exact verification agrees
EDGE_NEIGHBOURS, EDGE_COS = 12, np.cos(np.deg2rad(20.0))  # closure sampling: no contact where normals turn


@dataclass(frozen=True)
class Grasp:
    """A feasible hand configuration with every fingertip on the surface.

    Attributes:
        palm_pos (3,), palm_quat (4,) wxyz, q (D,): the hand.
        contacts (m, 3): surface points under the fingertips; normals (m, 3): outward normals there.
        penetration, self_overlap: the measured violations (m), both ≤ 1 mm.
    """

    palm_pos: np.ndarray
    palm_quat: np.ndarray
    q: np.ndarray
    contacts: np.ndarray
    normals: np.ndarray
    penetration: float
    self_overlap: float


def pad_directions(hand: Hand) -> np.ndarray:
    """(m, 3) unit "pad" direction of each fingertip in its link frame: the outward normal of the fingertip
    body's collision mesh at the contact point (the side of the finger that should face the object)."""
    if hand.name in _PADS:
        return _PADS[hand.name]
    out = np.zeros((hand.num_fingertips, 3))
    for i, link in enumerate(hand.fingertip_links):
        b, T = hand.tree.link_body[link]
        mesh = hand.collision_meshes.get(hand.tree.body_names[b])
        tip_body = T[:3, :3] @ hand.tip_offsets[i] + T[:3, 3]
        if mesh is None:
            d = hand.tip_offsets[i]
        else:
            _, _, face = trimesh.proximity.closest_point(mesh, tip_body[None])
            d = T[:3, :3].T @ np.asarray(mesh.face_normals)[face[0]]
        out[i] = d / max(np.linalg.norm(d), 1e-9)
    _PADS[hand.name] = out
    return out


_PADS: dict[str, np.ndarray] = {}


def pad_alignment(
    hand: Hand,
    palm_pos: torch.Tensor,
    palm_quat: torch.Tensor,
    q: torch.Tensor,
    normals: np.ndarray,
) -> np.ndarray:
    """(B, m) cosine between each fingertip's world pad direction and the surface normal there (−1: facing)."""
    poses = hand.link_poses(palm_pos, palm_quat, q)
    pads = pad_directions(hand)
    world = np.stack([poses[link][:, :3, :3].numpy() @ pads[i] for i, link in enumerate(hand.fingertip_links)], 1)
    cosine: np.ndarray = np.einsum("bij,bij->bi", world, normals)
    return cosine


def _rotation_to(a: np.ndarray, b: np.ndarray) -> Rotation:
    """A rotation taking unit vector a onto unit vector b."""
    rot, _ = Rotation.align_vectors(b[None], a[None])
    return rot


def sample_palms(
    hand: Hand,
    obj: ObjectField,
    size: float,
    count: int,
    rng: np.random.Generator,
) -> tuple[np.ndarray, np.ndarray]:
    """``count`` palm poses facing the object: positions (B, 3), quaternions (B, 4) wxyz."""
    pos0 = torch.zeros(1, 3, dtype=torch.float64)
    quat0 = torch.tensor([[1.0, 0.0, 0.0, 0.0]], dtype=torch.float64)
    tips = hand.fingertips(pos0, quat0, torch.as_tensor(hand.rest[None]))[0].numpy()
    centroid = tips.mean(axis=0)
    reach = max(float(centroid @ hand.approach_axis), 0.02)
    idx = rng.integers(len(obj.points), size=count)
    positions, quats = np.zeros((count, 3)), np.zeros((count, 4))
    for b, i in enumerate(idx):
        p, n = obj.points[i], obj.normals[i]
        tilt = Rotation.from_rotvec(_random_perpendicular(n, rng) * rng.uniform(0.0, MAX_TILT))
        d = tilt.apply(-n)
        rot = Rotation.from_rotvec(d * rng.uniform(-np.pi, np.pi)) * _rotation_to(hand.approach_axis, d)
        delta = rng.uniform(-min(0.45 * size, 0.8 * reach), 0.01)
        positions[b] = p + delta * n - rot.apply(centroid)
        x, y, z, w = rot.as_quat()
        quats[b] = (w, x, y, z)
    return positions, quats


def _random_perpendicular(n: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    v = rng.normal(size=3)
    v -= (v @ n) * n
    return v / max(float(np.linalg.norm(v)), 1e-12)


def _targets(obj: ObjectField, all_tips: np.ndarray, i: int, k: int, rng: np.random.Generator) -> np.ndarray:
    """(k, 3) surface targets near fingertip i, facing it, and nearer to it than to the other fingertips (by
    ``VORONOI_MARGIN``), so that fingers do not cross."""
    tips = all_tips[i]
    near = obj.tree.query_ball_point(tips, r=CANDIDATE_RADIUS)
    near = np.asarray(near, dtype=np.int64)
    if near.size:
        facing = near[np.einsum("ij,ij->i", tips - obj.points[near], obj.normals[near]) > 0]
        near = facing if facing.size else near
        d = np.linalg.norm(obj.points[near][:, None] - all_tips[None], axis=-1)
        others = np.delete(d, i, axis=1)
        if others.shape[1]:
            own = near[d[:, i] + VORONOI_MARGIN < others.min(axis=1)]
            near = own if own.size else near
    if not near.size:
        _, near = obj.tree.query(tips, k=k)
        near = np.atleast_1d(near)
    return obj.points[rng.choice(near, size=k)]


def sample_grasps(
    hand: Hand,
    obj: ObjectField,
    size: float,
    rng: np.random.Generator,
    *,
    palms: int = 12,
    candidates: int = 8,
    combos: int = 32,
    max_grasps: int = 8,
    closure_mu: float | None = None,
) -> list[Grasp]:
    """Feasible grasps of ``hand`` on ``obj`` by the hierarchical sampling of the module docstring.

    Args:
        closure_mu: when given, aim for force closure at this friction coefficient: pinching palms across
            antipodal pairs (`pinch.sample_pinch_palms`; fewer than ``palms``, or none, on objects the hand does
            not span), and combinations whose pad contacts fail the verification's closure tests (`_closure_rows`)
            dropped before the exact tests. The caller still verifies closure exactly.
    """
    joint_sets = finger_joint_sets(hand)
    groups = finger_groups(joint_sets)
    free_palm = len(groups) == 1 and len(groups[0]) > 1
    m, D = hand.num_fingertips, hand.dof
    if closure_mu is None:
        palm_pos, palm_quat = sample_palms(hand, obj, size, palms, rng)
    else:
        palm_pos, palm_quat = sample_pinch_palms(hand, obj, palms, closure_mu, rng)
        palms = len(palm_pos)
        if palms == 0:
            return []
    pp = torch.as_tensor(palm_pos).repeat_interleave(candidates, 0)
    pq = torch.as_tensor(palm_quat).repeat_interleave(candidates, 0)
    q0 = torch.as_tensor(np.tile(hand.rest, (palms * candidates, 1)))
    with torch.no_grad():
        rest_tips = hand.fingertips(
            torch.as_tensor(palm_pos), torch.as_tensor(palm_quat), torch.as_tensor(np.tile(hand.rest, (palms, 1)))
        ).numpy()
        targets = np.zeros((palms, candidates, m, 3))
        for b in range(palms):
            for i in range(m):
                targets[b, :, i] = _targets(obj, rest_tips[b], i, candidates, rng)
        pp, pq, q, _tips = solve_ik(
            hand, pp, pq, q0, torch.as_tensor(targets.reshape(-1, m, 3)), obj.surface, free_palm=free_palm
        )
    with torch.no_grad():
        pads, radii = pad_spheres(hand, pp, pq, q)
    phi, nrm, _ = obj.signed_distance(pads.reshape(-1, 3))
    ok = (np.abs(phi.reshape(-1, m) - radii[None]) <= TIP_TOL).reshape(palms, candidates, m)
    if not free_palm:
        with torch.no_grad():
            ok &= (pad_alignment(hand, pp, pq, q, nrm.reshape(-1, m, 3)) < -PAD_FACING).reshape(palms, candidates, m)
    q_np = q.numpy().reshape(palms, candidates, D)
    pp_np, pq_np = pp.numpy().reshape(palms, candidates, 3), pq.numpy().reshape(palms, candidates, 4)

    # combine per-group solutions
    rows_pos, rows_quat, rows_q = [], [], []
    for b in range(palms):
        if free_palm:
            for k in np.flatnonzero(ok[b].all(axis=1)):
                rows_pos.append(pp_np[b, k])
                rows_quat.append(pq_np[b, k])
                rows_q.append(q_np[b, k])
            continue
        good = [np.flatnonzero(ok[b][:, g].all(axis=1)) for g in groups]
        if any(len(g) == 0 for g in good):
            continue
        for _ in range(combos):
            qc = hand.rest.copy()
            for g, rows in zip(groups, good, strict=True):
                k = rng.choice(rows)
                cols = np.unique(np.concatenate([joint_sets[i] for i in g]))
                qc[cols] = q_np[b, k, cols]
            rows_pos.append(palm_pos[b])
            rows_quat.append(palm_quat[b])
            rows_q.append(qc)
    if not rows_q:
        return []
    P = torch.as_tensor(np.stack(rows_pos))
    Q = torch.as_tensor(np.stack(rows_quat))
    J = torch.as_tensor(np.stack(rows_q))
    with torch.no_grad():
        if not free_palm:
            J = separate(hand, P, Q, J, obj.surface)
        pads, radii = pad_spheres(hand, P, Q, J)
        over = self_overlap(hand, P, Q, J)
    gaps = np.linalg.norm(pads[:, :, None] - pads[:, None, :], axis=-1) + np.eye(m)[None] * 1e3
    keep = (over <= PENETRATION_TOL) & (gaps.min(axis=(1, 2)) >= MIN_CONTACT_GAP)
    phi_fast = obj.signed_distance(pads.reshape(-1, 3))[0].reshape(-1, m) - radii[None]
    keep &= (np.abs(phi_fast) <= TIP_TOL).all(axis=1)
    if closure_mu is not None:
        keep &= _closure_rows(hand, obj, pads, radii, keep, closure_mu)
    idx = np.flatnonzero(keep)
    rng.shuffle(idx)
    out: list[Grasp] = []
    for start in range(0, len(idx), 16):
        sel = idx[start : start + 16]
        with torch.no_grad():  # fast pre-filter (point-cloud field, every body within 3 mm)
            depth = penetration_depth(hand, obj, P[sel], Q[sel], J[sel])
        for j, d in zip(sel, depth, strict=True):
            if d > PREFILTER_TOL:
                continue
            exact = exact_checks(hand, obj, P[j].numpy(), Q[j].numpy(), J[j].numpy(), pads[j], radii)
            if exact is None:
                continue
            contacts, normals, pen, selfc = exact
            out.append(Grasp(P[j].numpy(), Q[j].numpy(), J[j].numpy(), contacts, normals, pen, selfc))
            if len(out) >= max_grasps:
                return out
    return out


def _closure_rows(
    hand: Hand, obj: ObjectField, pads: np.ndarray, radii: np.ndarray, rows: np.ndarray, mu: float
) -> np.ndarray:
    """(R,) bool: rows (of ``rows``) whose pad contacts (R, m, 3) pass the verification's closure tests at ``mu``
    (`manifoundation.core.refine.verify`: forces with Gf = 0 under the closure normalisation, and Ferrari–Canny ε above
    ``CLOSURE_MIN_EPSILON``), on the dense cloud's normals."""
    from manifoundation.core.refine.verify import RESIDUAL_SQ_TOL, contact_quality, produces_wrench
    from manifoundation.core.refine.wrench import closure_task

    centre = obj.points.mean(axis=0)
    task = closure_task(centre, float(np.max(np.linalg.norm(obj.points - centre, axis=1))))
    out = np.zeros(len(rows), dtype=bool)
    idx = np.flatnonzero(rows)
    if not idx.size:
        return out
    contacts, normals = _pad_contacts(obj, pads[idx].reshape(-1, 3), np.tile(radii, len(idx)))
    _, near = obj.tree.query(contacts, k=EDGE_NEIGHBOURS)
    # a contact on an edge: its normal depends on the cloud, so the verification may disagree
    on_edge = (np.einsum("nkj,nj->nk", obj.normals[near], normals).min(axis=1) < EDGE_COS).reshape(len(idx), -1)
    contacts, normals = contacts.reshape(len(idx), -1, 3), normals.reshape(len(idx), -1, 3)
    for i, r in enumerate(idx):
        if on_edge[i].any():
            continue
        sol, eps = contact_quality(hand, contacts[i], normals[i], task, mu, epsilon_below=RESIDUAL_SQ_TOL)
        out[r] = produces_wrench(sol) and eps >= CLOSURE_MIN_EPSILON
    return out


def _pad_contacts(obj: ObjectField, pads: np.ndarray, radii: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Contact points (M, 3) = the surface points under pad spheres (M, 3) of radii (M,), and their normals."""
    _, nrm, _ = obj.signed_distance(pads)
    return obj.surface(pads - radii[:, None] * nrm)


def exact_checks(
    hand: Hand,
    obj: ObjectField,
    palm_pos: np.ndarray,
    palm_quat: np.ndarray,
    q: np.ndarray,
    pads: np.ndarray,
    radii: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, float, float] | None:
    """The verification's own tests (`manifoundation.core.geometry`, fcl on the collision meshes; exact mesh distance of
    the pad spheres): contacts (m, 3) = pad points nearest the surface, normals, penetration, self-collision; None
    when a test fails."""
    dist = obj.exact_signed_distance(pads) - radii
    if np.max(np.abs(dist)) > TIP_TOL:
        return None
    from manifoundation.core.geometry import ObjectGeometry, hand_object_penetration, hand_self_collision

    geom = ObjectGeometry.from_points(obj.points, obj.normals, obj.mesh)
    pen = float(hand_object_penetration(hand, geom, palm_pos, palm_quat, q))
    if pen > PENETRATION_TOL:
        return None
    selfc = float(hand_self_collision(hand, palm_pos, palm_quat, q))
    if selfc > PENETRATION_TOL:
        return None
    surf, nrm = _pad_contacts(obj, pads, radii)
    return surf, nrm, pen, selfc
