"""Hand configuration, the object's distance field protocol, and the local model at one iterate."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any

import numpy as np
import torch

from manifoundation.core.refine.contact import ObjectField, contact_jacobians, surface_contacts
from manifoundation.core.refine.forces import ForceSolution, solve_forces
from manifoundation.core.refine.self_pairs import near_pairs
from manifoundation.core.refine.wrench import WrenchTask
from manifoundation.core.robots.kinematics import one_cpu_pose, one_pose_values
from manifoundation.core.robots.kinematics_kernels import on_bodies_one

if TYPE_CHECKING:
    from manifoundation.core.robots.hand import Hand



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

    def step(self, hand: Hand, delta: np.ndarray) -> HandPose:
        """Apply δ (6 + D) with the hand's exponential map (palm rotation in the world frame)."""
        pos, quat, q = hand.apply_delta(*self.tensors(), torch.as_tensor(delta, dtype=torch.float64)[None])
        return HandPose(pos[0].numpy().copy(), quat[0].numpy().copy(), q[0].numpy().copy())


@dataclass(frozen=True)
class Jacobians:
    """The Jacobians of a `Linearisation` (its fields of the same names)."""

    tip_jac: np.ndarray
    gap_jac: np.ndarray
    normal_jac: np.ndarray
    sph_jac: np.ndarray
    clear_jac: np.ndarray


@dataclass
class Linearisation:
    """Everything the SCP step needs at one iterate (all numpy, float64).

    Attributes:
        tips, tip_jac: (m, 3), (m, 3, n) each fingertip's contact: its contact sample on the real finger surface
            (`manifoundation.core.refine.contact`) projected onto the object (where the force acts, as verification has
            it), and the sample's Jacobian (n = 6 + D).
        tip_phi, tip_grad, gap_jac: (m,), (m, 3), (m, 3, n) distance the objective drives to zero (Φ, or Φ^R with a
            mask) at each pad's sample nearest the object, its gradient and that sample's Jacobian.
        normals: (m, 3) the object's given outward normal at each contact (grasp maps, friction cones).
        normal_jac: (m, 3, 3) ∂n/∂p at the tips, from the smoothed normal (zeros without a curvature model).
        forces: f* (m, 3) and the inner solution.
        clear, clear_grad, clear_jac: (R,), (R, 3), (R, 3, n) clearance to the object of the hand–object guards —
            the fingertip bodies' surface samples nearest the object (radius 0) and the other bodies' collision
            spheres (Φ(centre) − r) — with their gradients and Jacobians.
        sph, sph_jac, sph_radius: every collision sphere (S) and its Jacobian (self-collision pairs).
        pair_idx, pair_dist, pair_dir: self-collision pairs (P, 2), their centre distances and unit directions: the
            hand's pairs within `manifoundation.core.refine.self_pairs.PAIR_REACH` of touching (the others cannot
            overlap nor enter the step's rows).
        q, lower, upper: joint values and limits (D,).
        region_point: with a region mask, each contact point's distance to the nearest allowed sample (m,) — the
            verification's region test, which the convergence test also applies (Φ^R is to the samples' discs).
        contact_gap: (m,) Φ less the standoff at the contact samples (where the force acts and verification
            measures, up to ``CONTACT_TIE`` farther than the pad's nearest sample); the convergence test asks it.
        pending: without Jacobians (``linearise(..., jacobian=False)``: tip_jac, gap_jac, normal_jac, clear_jac
            and sph_jac are empty), what computes them (`completed`).
        samples: (m, 3) the contact samples on the fingers that ``tips`` are projected from.
    """

    task: WrenchTask
    mu: float
    max_normal_force: float
    tips: np.ndarray
    tip_jac: np.ndarray
    tip_phi: np.ndarray
    tip_grad: np.ndarray
    gap_jac: np.ndarray
    normals: np.ndarray
    normal_jac: np.ndarray
    solution: ForceSolution
    clear: np.ndarray
    clear_grad: np.ndarray
    clear_jac: np.ndarray
    sph: np.ndarray
    sph_jac: np.ndarray
    sph_radius: np.ndarray
    pair_idx: np.ndarray
    pair_dist: np.ndarray
    pair_dir: np.ndarray
    q: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    region_point: np.ndarray | None = None
    contact_gap: np.ndarray | None = None
    pending: Callable[[], Jacobians] | None = None
    samples: np.ndarray | None = None

    def completed(self) -> Linearisation:
        """This linearisation with its Jacobians: itself, or (``linearise(..., jacobian=False)``) a copy with them
        computed now."""
        if self.pending is None:
            return self
        j = self.pending()
        return replace(self, pending=None, tip_jac=j.tip_jac, gap_jac=j.gap_jac, normal_jac=j.normal_jac,
                       sph_jac=j.sph_jac, clear_jac=j.clear_jac)  # fmt: skip

    @property
    def forces(self) -> np.ndarray:
        return self.solution.forces

    @property
    def residual_norm(self) -> float:
        return self.solution.residual_norm

    def penetration(self) -> np.ndarray:
        """Per-guard penetration into the object (≥ 0)."""
        depth: np.ndarray = np.maximum(0.0, -self.clear)
        return depth

    def self_overlap(self) -> np.ndarray:
        """Per-pair overlap of self-collision spheres (≥ 0)."""
        if not len(self.pair_idx):
            return np.zeros(0)
        r = self.sph_radius[self.pair_idx].sum(axis=1)
        overlap: np.ndarray = np.maximum(0.0, r - self.pair_dist)
        return overlap


def body_spheres(hand: Hand) -> np.ndarray:
    """Indices of the collision spheres that guard hand–object contact: those not on a fingertip body (the
    fingertip bodies are guarded by samples of their real surface, which the spheres would hold off it)."""
    return np.flatnonzero(np.asarray(hand.sphere_fingertip) < 0)


def sphere_kinematics(
    hand: Hand, pose: tuple[torch.Tensor, torch.Tensor, torch.Tensor], body_poses: torch.Tensor | None,
    jacobian: bool = True,
) -> tuple[torch.Tensor, torch.Tensor | None]:  # fmt: skip
    """Collision-sphere centres (1, S, 3) and Jacobians (1, S, 3, n) (None without ``jacobian``), as
    `Hand.spheres` computes them, from body poses (1, nb, 4, 4) the contact model already has (the forward
    kinematics once an iterate, not twice)."""
    if body_poses is None:
        pts, jac = hand.spheres(*pose)
        return pts, jac if jacobian else None
    cache = hand.__dict__.setdefault("_sphere_kinematics", {})
    key = (body_poses.dtype, body_poses.device)
    if key not in cache:
        bodies = np.asarray([hand.tree.body_names.index(link) for link in hand.sphere_links], dtype=np.int64)
        local = torch.as_tensor(hand.sphere_centres, dtype=body_poses.dtype, device=body_poses.device)
        cache[key] = (bodies, torch.as_tensor(bodies, device=body_poses.device), local)
    bodies, index, local = cache[key]
    if one_cpu_pose(body_poses):
        pts = torch.from_numpy(on_bodies_one(one_pose_values(body_poses), bodies, local.numpy(), True))[None]
    else:
        Tb = body_poses[:, index]
        pts = (Tb[..., :3, :3] @ local[..., None])[..., 0] + Tb[..., :3, 3]
    return pts, hand.tree.point_jacobian(body_poses, bodies, pts, pose[0]) if jacobian else None


def linearise(
    hand: Hand,
    pose: HandPose,
    field: ObjectField,
    task: WrenchTask,
    mu: float,
    max_normal_force: float,
    tip_field: Any | None = None,
    jacobian: bool = True,
    exact: bool = False,
) -> Linearisation:
    """Kinematics, distances and optimal forces at ``pose``.

    Args:
        hand: a `manifoundation.core.robots.Hand`.
        pose: the iterate.
        field: object signed distance, given and smoothed normals (`manifoundation.core.refine.field.PointCloudField`).
        task: residual definition.
        mu, max_normal_force: friction and force bound.
        tip_field: optional callable ``x -> (Φ^R, ∇Φ^R)`` used instead of Φ for the tip objective (masks).
        jacobian: False leaves the Jacobians to `Linearisation.completed` (a candidate's merit needs none of them:
            the refinement completes only the accepted ones).
        exact: the contacts on the object's mesh (where the field has one), not projected on the points' surface.
    """
    tensors = pose.tensors()
    contacts = surface_contacts(hand, tensors, field, tip_field, jacobian=jacobian)
    with torch.no_grad():
        sph_t, sph_jac_t = sphere_kinematics(hand, tensors, contacts.body_poses, jacobian=jacobian)
    sph = sph_t[0].numpy()
    radius = np.asarray(hand.sphere_radii, dtype=np.float64)
    guard = body_spheres(hand)
    sph_phi, sph_grad, _ = field.signed_distance(sph[guard])
    tips = contacts.points
    on_object = contacts.object_points(field, exact)
    normals = field.given_normal(on_object)

    def jacobians() -> Jacobians:
        m = len(tips)
        if contacts.jac is not None and contacts.gap_jac is not None and contacts.row_jac is not None:
            jac, gap_jac, row_jac = contacts.jac, contacts.gap_jac, contacts.row_jac
        else:
            assert contacts.body_poses is not None and contacts.jacobian_request is not None
            jac, gap_jac, row_jac = contact_jacobians(hand, contacts.body_poses, tensors[0],
                                                      contacts.jacobian_request, m)  # fmt: skip
        if sph_jac_t is not None:
            sph_jac = sph_jac_t[0].numpy()
        else:
            with torch.no_grad():
                sph_jac_full = sphere_kinematics(hand, tensors, contacts.body_poses)[1]
            assert sph_jac_full is not None
            sph_jac = sph_jac_full[0].numpy()
        has_curvature = hasattr(field, "normal_jacobian")
        normal_jac = field.normal_jacobian(tips) if has_curvature else np.zeros((m, 3, 3))  # type: ignore[attr-defined]
        return Jacobians(jac, gap_jac, normal_jac, sph_jac, np.concatenate([row_jac, sph_jac[guard]]))

    n = 6 + hand.dof
    empty = np.zeros((0, 3, n))
    done = jacobians() if jacobian else Jacobians(empty, empty, np.zeros((0, 3, 3)), empty, empty)
    point_distance = getattr(field, "region_point_distance", None) if tip_field is not None else None
    solution = solve_forces(task, on_object, normals, mu, max_normal_force)  # where verification applies them
    every_pair = np.asarray(hand.self_collision_pairs, dtype=np.int64).reshape(-1, 2)
    near, dist, direction = near_pairs(sph, radius, every_pair)  # only the pairs within reach (`self_pairs`)
    return Linearisation(
        task=task,
        mu=mu,
        max_normal_force=max_normal_force,
        tips=on_object,
        samples=tips,
        tip_jac=done.tip_jac,
        tip_phi=contacts.phi,
        tip_grad=contacts.grad,
        gap_jac=done.gap_jac,
        normals=np.asarray(normals, dtype=np.float64),
        normal_jac=done.normal_jac,
        solution=solution,
        clear=np.concatenate([contacts.clear, sph_phi - radius[guard]]),
        clear_grad=np.concatenate([contacts.clear_grad, sph_grad]),
        clear_jac=done.clear_jac,
        sph=sph,
        sph_jac=done.sph_jac,
        sph_radius=radius,
        pair_idx=every_pair[near],
        pair_dist=dist,
        pair_dir=direction,
        q=pose.q,
        lower=np.asarray(hand.lower, dtype=np.float64),
        upper=np.asarray(hand.upper, dtype=np.float64),
        region_point=None if point_distance is None else np.asarray(point_distance(on_object), dtype=np.float64),
        contact_gap=contacts.point_gap if tip_field is None else None,
        pending=None if jacobian else jacobians,
    )
