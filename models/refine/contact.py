"""The contact model on the real fingertip surfaces, shared by refinement, the grasp sampler and verification.

A fingertip's contact is the sample of its pad (`models.robots.pads`: evenly spaced samples of the fingertip body's
collision mesh near its tip point) nearest to the object: the smallest Φ (or, with a region mask, the smallest
Φ^R). Its gap to the object is that Φ (negative: the finger surface is inside), its Jacobian the sample's point
Jacobian, and the contact on the object is the sample projected along the surface normal. All samples of a
fingertip body guard it against penetration (Φ ≥ 0); the other bodies keep their collision spheres.

The friction cones use the object's normals as given: the normal of the caller's point nearest the contact
(`PointCloudField.given_normal`), never a re-estimated or smoothed one.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Protocol

import numpy as np
import torch

GUARD_ROWS_PER_FINGERTIP = 24
"""At most this many of a fingertip body's samples (the nearest to the object) enter the step's rows."""
CONTACT_TIE = 1.5e-3
"""m: pad samples this close to the nearest one are equally in contact (a patch): the one nearest the tip point is
the contact (on a flat pad against a flat face an arbitrary pick put a gripper's two contacts 2.4 cm apart)."""
GUARD_MARGIN = 0.02
"""m: samples (and spheres) farther than this from the object are not measured in detail."""

TipField = Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]]


class ObjectField(Protocol):
    """What the contact model needs from the object (`models.refine.field.PointCloudField` satisfies it)."""

    def signed_distance(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(M, 3) → Φ (M,), ∇Φ (M, 3), nearest sample (M, 3)."""
        ...

    def given_normal(self, x: np.ndarray) -> np.ndarray:
        """(M, 3) → the caller's outward normal (M, 3) of the sample nearest each x."""
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
        guard_phi: (G,) Φ of the guard samples measured in detail; guard_rows: (R,) positions in ``guard_phi`` of
            the samples that enter the step's rows, with row_grad (R, 3) and row_jac (R, 3, n).
    """

    sample: np.ndarray
    points: np.ndarray
    jac: np.ndarray | None
    nearest: np.ndarray
    gap_jac: np.ndarray | None
    phi: np.ndarray
    grad: np.ndarray
    gap: np.ndarray
    guard_phi: np.ndarray
    guard_rows: np.ndarray
    row_grad: np.ndarray
    row_jac: np.ndarray | None

    def object_points(self, field: ObjectField) -> np.ndarray:
        """(m, 3) the contacts projected onto the object's surface."""
        phi, grad, _ = field.signed_distance(self.points)
        return np.asarray(self.points - phi[:, None] * grad)


def surface_contacts(
    hand: object, pose: tuple[torch.Tensor, torch.Tensor, torch.Tensor], field: ObjectField,
    tip_field: TipField | None = None, jacobian: bool = True, margin: float = GUARD_MARGIN,
) -> SurfaceContacts:  # fmt: skip
    """Measure the fingertips' real surfaces against the object at ``pose`` (batch-of-one tensors).

    Args:
        hand: a `models.robots.Hand`.
        pose: (palm_pos (1, 3), palm_quat (1, 4), q (1, D)) float64 tensors.
        field: the object's signed distance and given normals.
        tip_field: Φ^R for a region mask (the contact is the pad sample nearest the region).
        jacobian: also return the Jacobians (refinement); verification and sampling do without.
        margin: guards farther than this from the object are left out of the rows.
    """
    surf = hand.contact_surface  # type: ignore[attr-defined]
    with torch.no_grad():
        world_t, _, _ = hand.surface_samples(*pose, jacobian=False)  # type: ignore[attr-defined]
    world = world_t[0].numpy()
    m = len(surf.bound_radius)
    # cull: the bodies whose bounding sphere is far from the object only need their pads measured
    centres = np.stack([world[surf.fingertip == i].mean(0) for i in range(m)])
    centre_phi = field.signed_distance(centres)[0]
    near_body = centre_phi < surf.bound_radius * 2.0 + margin
    measure = np.flatnonzero(surf.pad | near_body[surf.fingertip])
    phi_all, grad_all, _ = field.signed_distance(world[measure])
    score = phi_all if tip_field is None else tip_field(world[measure])[0]
    sample = np.zeros(m, dtype=np.int64)
    nearest = np.zeros(m, dtype=np.int64)
    owner = surf.fingertip[measure]
    pad = surf.pad[measure]
    rows: list[np.ndarray] = []
    for i in range(m):
        mine = np.flatnonzero((owner == i) & pad)
        nearest[i] = measure[mine[np.argmin(score[mine])]]
        tied = mine[score[mine] <= score[mine].min() + CONTACT_TIE]
        sample[i] = measure[tied[np.argmin(surf.tip_distance[measure[tied]])]]
        if near_body[i]:
            body = np.flatnonzero((owner == i) & (phi_all < margin))
            rows.append(body[np.argsort(phi_all[body])[:GUARD_ROWS_PER_FINGERTIP]])
    at = np.searchsorted(measure, nearest)  # ``measure`` is sorted (np.flatnonzero)
    points = world[sample]
    gap = phi_all[at]
    if tip_field is None:
        phi, grad = gap.copy(), grad_all[at].copy()
    else:
        phi, grad = tip_field(world[nearest])
    guard_rows = np.concatenate(rows) if rows else np.zeros(0, dtype=np.int64)
    jac = gap_jac = row_jac = None
    if jacobian:
        wanted = np.concatenate([sample, nearest, measure[guard_rows]])
        with torch.no_grad():
            _, _, j_t = hand.surface_samples(*pose, index=wanted)  # type: ignore[attr-defined]
        assert j_t is not None
        full = j_t[0].numpy()
        jac, gap_jac, row_jac = full[:m], full[m : 2 * m], full[2 * m :]
    return SurfaceContacts(
        sample=sample, points=points, jac=jac, nearest=nearest, gap_jac=gap_jac, phi=np.asarray(phi, dtype=np.float64),
        grad=np.asarray(grad, dtype=np.float64), gap=np.asarray(gap, dtype=np.float64),
        guard_phi=np.asarray(phi_all, dtype=np.float64), guard_rows=guard_rows,
        row_grad=np.asarray(grad_all[guard_rows], dtype=np.float64), row_jac=row_jac,
    )  # fmt: skip
