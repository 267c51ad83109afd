"""The contact model on the real fingertip surfaces, shared by refinement, the grasp sampler and verification.

A fingertip's contact is the sample of its pad (`manifoundation.core.robots.pads`: evenly spaced samples of the
fingertip body's collision mesh near its tip point) nearest to the object: the smallest Φ (or, with a region mask, the
smallest Φ^R). Its gap to the object is that Φ (negative: the finger surface is inside), its Jacobian the sample's point
Jacobian, and the contact on the object is the sample projected along the surface normal. All samples of a fingertip
body guard it against penetration (Φ ≥ 0); the other bodies keep their collision spheres.

The friction cones use the object's normals as given: the normal of the caller's point nearest the contact
(`PointCloudField.given_normal`), never a re-estimated or smoothed one.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np
import torch

from manifoundation.core.refine.cover import deciding_samples, sample_cover
from manifoundation.core.refine.object_guards import object_balls, object_guards, part_boxes_of, part_grids_of

GUARD_ROWS_PER_FINGERTIP = 24
"""At most this many of a fingertip body's samples (the nearest to the object) enter the step's rows."""
CONTACT_TIE = 1.5e-3
"""m: pad samples this close to the nearest one are equally in contact (a patch): the one nearest the tip point is
the contact (on a flat pad against a flat face an arbitrary pick put a gripper's two contacts 2.4 cm apart)."""
GUARD_MARGIN = 0.02
"""m: samples (and spheres) farther than this from the object are not measured in detail."""
GUARD_STANDOFF = 5e-4
"""m: the guards keep the sampled surface this far out, and the objective brings the pad this close: between the
2.5 mm samples the real mesh reaches up to ~0.5 mm nearer (verification measured 1.05 mm where they read 0.5).
A field with a coarser ``resolution`` (the object's points: their disc radius) sets a larger standoff: the exact
surface may reach that far beyond what its points show (a block's corner poked 1.4 mm into a finger)."""

TipField = Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]]


class ObjectField(Protocol):
    """What the contact model needs from the object.

    `manifoundation.core.refine.field.PointCloudField` satisfies it.
    """

    def signed_distance(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(M, 3) → Φ (M,), ∇Φ (M, 3), nearest sample (M, 3)."""
        ...

    def given_normal(self, x: np.ndarray) -> np.ndarray:
        """(M, 3) → the caller's outward normal (M, 3) of the sample nearest each x."""
        ...

    @property
    def points(self) -> np.ndarray:
        """(N, 3) the object's points."""
        ...


@dataclass
class SurfaceContacts:
    """Per fingertip (m of them), the contact on its real surface, and the guards of its body.

    Attributes:
        sample: (m,) index into ``hand.contact_surface`` of each fingertip's contact sample: of the pad samples
            within ``CONTACT_TIE`` of the nearest, the one nearest the tip point (where the force acts).
        points: (m, 3) the contact samples (on the finger). jac: (m, 3, n) their Jacobians (None if not asked).
        nearest: (m,) each pad's sample nearest the object (smallest score); gap_jac (m, 3, n) its Jacobian.
        phi: (m,) the distance the objective drives to zero: the nearest sample's Φ (or Φ^R with a region), a
            minimum of smooth functions. grad: (m, 3) its gradient.
        gap: (m,) each pad's signed distance Φ to the object: its nearest sample's (negative inside).
        point_gap: (m,) Φ of each contact sample less the standoff (verification measures the contact there).
        clear, clear_grad, row_jac: (R,), (R, 3), (R, 3, n) the guards' clearances (negative: penetrating), the
            direction a finger point moves to increase each, and that point's Jacobian: the fingertip bodies'
            samples nearest the object (Φ, ∇Φ), and object points near a fingertip measured against the convex
            parts of its body (`manifoundation.core.refine.object_guards`) — a sharp object edge poking into a flat
            finger face between samples (1.8 mm deep where the samples read 0.45 mm, LEAP on the example box).
        projected: (m, 3) the contacts projected onto the object, from the samples' own distances.
        body_poses: (1, nb, 4, 4) the hand's body poses at this pose (the linearisation's spheres reuse them).
        jacobian_request: the points (P, 3) and their bodies (P,) whose Jacobians make ``jac``, ``gap_jac``,
            ``row_jac`` (`contact_jacobians`; a refinement asks for them only once a candidate is accepted).
    """

    sample: np.ndarray
    points: np.ndarray
    jac: np.ndarray | None
    nearest: np.ndarray
    gap_jac: np.ndarray | None
    phi: np.ndarray
    grad: np.ndarray
    gap: np.ndarray
    point_gap: np.ndarray
    clear: np.ndarray
    clear_grad: np.ndarray
    row_jac: np.ndarray | None
    projected: np.ndarray | None = None
    body_poses: torch.Tensor | None = None
    jacobian_request: tuple[np.ndarray, np.ndarray] | None = None

    def object_points(self, field: ObjectField, exact: bool = False) -> np.ndarray:
        """(m, 3) the contacts projected onto the object's surface (measured with the samples when they were:
        ``projected``; the field is asked again only without them); ``exact``: the closest points on the
        object's mesh where the field has one (``field.exact``, what verification measures)."""
        surface = getattr(field, "exact", None) if exact else None
        if surface is not None:
            return np.asarray(surface.closest(self.points)[0])
        if self.projected is not None:
            return self.projected
        phi, grad, _ = field.signed_distance(self.points)
        return np.asarray(self.points - phi[:, None] * grad)


def field_standoff(field: ObjectField) -> float:
    """The guards' standoff and the pads' target distance (m) for ``field``: `GUARD_STANDOFF` or the field's
    ``resolution``, whichever is larger, unless the field sets its own ``standoff`` (the closing stage,
    `manifoundation.core.refine.close`)."""
    own = getattr(field, "standoff", None)
    if own is not None:
        return float(own)
    return max(GUARD_STANDOFF, float(getattr(field, "resolution", 0.0)))


def contact_jacobians(
    hand: Any, body_poses: torch.Tensor, palm_pos: torch.Tensor, request: tuple[np.ndarray, np.ndarray], m: int,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:  # fmt: skip
    """``jac`` (m, 3, n), ``gap_jac`` (m, 3, n), ``row_jac`` (R, 3, n) of `surface_contacts`: one point Jacobian for
    the contact samples, the pads' nearest samples, the guard samples and the guards' feet (its per-body terms
    once), from the body poses (1, nb, 4, 4) and the palm position (1, 3) of the pose."""
    points, bodies = request
    at_points = torch.as_tensor(points, dtype=body_poses.dtype)[None]
    with torch.no_grad():
        full = hand.tree.point_jacobian(body_poses, bodies, at_points, palm_pos)[0].numpy()
    return full[:m], full[m : 2 * m], full[2 * m :]


def _fingertip_members(hand: Any, surf: Any) -> list[np.ndarray | slice]:
    """Per fingertip, its samples in ``surf`` (the hand's contact surface, a cached property): a slice where they
    are contiguous (they are, for the built-in hands), else their indices; cached on the hand (the boolean mask
    cost 0.3 ms an iterate)."""
    if "_fingertip_members" not in hand.__dict__:
        members: list[np.ndarray | slice] = []
        for i in range(len(surf.bound_radius)):
            idx = np.flatnonzero(surf.fingertip == i)
            contiguous = len(idx) and idx[-1] - idx[0] + 1 == len(idx)
            members.append(slice(int(idx[0]), int(idx[-1]) + 1) if contiguous else idx)
        hand.__dict__["_fingertip_members"] = members
    result: list[np.ndarray | slice] = hand.__dict__["_fingertip_members"]
    return result


def surface_contacts(
    hand: object, pose: tuple[torch.Tensor, torch.Tensor, torch.Tensor], field: ObjectField,
    tip_field: TipField | None = None, jacobian: bool = True, margin: float = GUARD_MARGIN, guards: bool = True,
    bounded: bool = True,
) -> SurfaceContacts:  # fmt: skip
    """Measure the fingertips' real surfaces against the object at ``pose`` (batch-of-one tensors).

    Args:
        hand: a `manifoundation.core.robots.Hand`.
        pose: (palm_pos (1, 3), palm_quat (1, 4), q (1, D)) float64 tensors.
        field: the object's signed distance and given normals.
        tip_field: Φ^R for a region mask (the contact is the pad sample nearest the region).
        jacobian: also return the Jacobians (refinement); verification and sampling do without.
        margin: guards farther than this from the object are left out of the rows.
        guards: also measure the guards (refinement); without them (verification: only the contacts) just the
            pads are measured — the same contacts, without the other samples' distances or the object points.
        bounded: measure only the samples that can decide the contacts and guard rows, bounded by their
            representatives' distances (`manifoundation.core.refine.cover`); False measures every pad and near-body
            sample.
    """
    surf = hand.contact_surface  # type: ignore[attr-defined]
    standoff = field_standoff(field)
    with torch.no_grad():  # the body poses once: the samples, the parts' poses and the Jacobians all use them
        T_all = hand.tree.body_poses(*pose)  # type: ignore[attr-defined]
        world_t, _, _ = hand.surface_samples(*pose, jacobian=False, body_poses=T_all)  # type: ignore[attr-defined]
    world = world_t[0].numpy()
    tip_body = hand.fingertip_body_index  # type: ignore[attr-defined]
    m = len(surf.bound_radius)
    # cull: the bodies whose bounding sphere is far from the object only need their pads measured
    centres = np.stack([world[members].mean(0) for members in _fingertip_members(hand, surf)])
    centre_phi = field.signed_distance(centres)[0]
    near_body = (centre_phi < surf.bound_radius * 2.0 + margin) & guards
    asked = surf.pad | near_body[surf.fingertip]
    if bounded:
        measure, phi_all, grad_all = deciding_samples(field, world, asked, near_body, margin, tip_field is not None,
                                                      surf, sample_cover(hand), CONTACT_TIE,
                                                      GUARD_ROWS_PER_FINGERTIP)  # fmt: skip
    else:
        measure = np.flatnonzero(asked)
        phi_all, grad_all, _ = field.signed_distance(world[measure])
    score = phi_all if tip_field is None else tip_field(world[measure])[0]
    sample = np.zeros(m, dtype=np.int64)
    nearest = np.zeros(m, dtype=np.int64)
    owner = surf.fingertip[measure]
    pad = surf.pad[measure]
    rows: list[np.ndarray] = []
    extra: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []
    body_T = T_all[0].numpy()[tip_body]  # numpy indexing: a torch index tensor cost ≈ 0.1 ms an iterate
    grids = part_grids_of(hand) if near_body.any() else [None] * m
    boxes = part_boxes_of(hand) if near_body.any() else [None] * m
    near_tips = np.flatnonzero(near_body)
    near_balls = object_balls(field, centres[near_tips], surf.bound_radius[near_tips])
    balls = dict(zip(near_tips.tolist(), near_balls, strict=True))
    for i in range(m):
        mine = np.flatnonzero((owner == i) & pad)
        nearest[i] = measure[mine[np.argmin(score[mine])]]
        tied = mine[score[mine] <= score[mine].min() + CONTACT_TIE]
        sample[i] = measure[tied[np.argmin(surf.tip_distance[measure[tied]])]]
        if near_body[i]:
            body = np.flatnonzero((owner == i) & (phi_all < margin))
            rows.append(body[np.argsort(phi_all[body])[:GUARD_ROWS_PER_FINGERTIP]])
            extra.append(object_guards(field, hand.fingertip_parts[i], body_T[i], centres[i],  # type: ignore[attr-defined]
                                        float(surf.bound_radius[i]), grids[i], balls[i], boxes[i]))  # fmt: skip
    at = np.searchsorted(measure, nearest)  # ``measure`` is sorted (np.flatnonzero)
    points = world[sample]
    gap = phi_all[at]
    at_sample = np.searchsorted(measure, sample)
    point_gap = phi_all[at_sample] - standoff
    projected = points - phi_all[at_sample, None] * grad_all[at_sample]
    if tip_field is None:
        phi, grad = gap - standoff, grad_all[at].copy()
    else:
        phi, grad = tip_field(world[nearest])
    guard_rows = np.concatenate(rows) if rows else np.zeros(0, dtype=np.int64)
    clear = np.concatenate([phi_all[guard_rows], *(e[0] for e in extra)]) - standoff
    clear_grad = np.concatenate([grad_all[guard_rows], *(e[1] for e in extra)]).reshape(-1, 3)
    guard_sample = measure[guard_rows]
    feet = np.concatenate([np.zeros((0, 3)), *(e[2] for e in extra)])
    foot_body = np.concatenate([np.zeros(0, dtype=np.int64)] + [
        np.full(len(e[2]), tip_body[i]) for i, e in zip(np.flatnonzero(near_body), extra, strict=True)
    ])  # fmt: skip
    jac = gap_jac = row_jac = None
    wanted = np.concatenate([sample, nearest, guard_sample])
    request = (np.concatenate([world[wanted], feet]), np.concatenate([surf.body[wanted], foot_body]))
    if jacobian:
        jac, gap_jac, row_jac = contact_jacobians(hand, T_all, pose[0], request, m)
    return SurfaceContacts(
        sample=sample, points=points, jac=jac, nearest=nearest, gap_jac=gap_jac, phi=np.asarray(phi, dtype=np.float64),
        grad=np.asarray(grad, dtype=np.float64), gap=np.asarray(gap, dtype=np.float64),
        point_gap=np.asarray(point_gap, dtype=np.float64),
        clear=np.asarray(clear, dtype=np.float64), clear_grad=np.asarray(clear_grad, dtype=np.float64),
        row_jac=row_jac, projected=np.asarray(projected, dtype=np.float64), body_poses=T_all,
        jacobian_request=request,
    )  # fmt: skip
