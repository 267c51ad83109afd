"""The paper's direct-grasp baseline: open hand, move towards the object centre, close fingers until contact.


From the start pose (fingers at rest = open) the palm translates towards the object centre in 5 mm steps until
any non-fingertip sphere or fingertip touches the object (Φ ≤ radius, resp. Φ(tip) ≤ 2 mm), or the palm would
pass the centre. Then every finger "closes": its own joints (the Jacobian columns that move its tip) follow the
gradient that brings its tip towards the surface, in steps of at most 0.05 rad, until its tip is within 2 mm or
any of its spheres touches; joints stay in their limits. Forces come from Eq. (6-8) at the final fingertips;
`manifoundation.core.refine.verify` judges the result like any other.
"""

from __future__ import annotations

import time
from typing import TYPE_CHECKING

import numpy as np
import torch

from manifoundation.core.refine.contact import surface_contacts
from manifoundation.core.refine.field import PointCloudField
from manifoundation.core.refine.state import HandPose, body_spheres

if TYPE_CHECKING:
    from manifoundation.core.robots.hand import Hand

CONTACT = 2e-3


def _spheres_touch(hand: Hand, pose: HandPose, cloud: PointCloudField, which: np.ndarray) -> np.ndarray:
    with torch.no_grad():
        sph = hand.spheres(*pose.tensors(), jacobian=False)[0][0].numpy()
    phi = cloud.signed_distance(sph[which])[0]
    return np.asarray(phi <= np.asarray(hand.sphere_radii)[which])


def _fingertips_touch(hand: Hand, pose: HandPose, cloud: PointCloudField) -> np.ndarray:
    """(m,) each fingertip's real surface is within ``CONTACT`` of the object."""
    found = surface_contacts(hand, pose.tensors(), cloud, jacobian=False)
    return np.asarray(found.gap <= CONTACT)


def direct_grasp(
    hand: Hand, cloud: PointCloudField, start: HandPose, centre: np.ndarray, max_steps: int = 200
) -> tuple[HandPose, float]:
    """Run the baseline from ``start``; returns (final pose, seconds)."""
    t0 = time.perf_counter()
    pose = HandPose(start.palm_pos.copy(), start.palm_quat.copy(), np.asarray(hand.rest, dtype=np.float64).copy())
    others = body_spheres(hand)
    n = 6 + hand.dof
    # approach
    for _ in range(max_steps):
        to_centre = centre - pose.palm_pos
        dist = float(np.linalg.norm(to_centre))
        if dist < 5e-3:
            break
        if np.any(_fingertips_touch(hand, pose, cloud)) or np.any(_spheres_touch(hand, pose, cloud, others)):
            break
        delta = np.zeros(n)
        delta[:3] = to_centre / dist * min(5e-3, dist)
        pose = pose.step(hand, delta)
    # close each finger
    lower, upper = np.asarray(hand.lower), np.asarray(hand.upper)
    done = np.zeros(hand.num_fingertips, dtype=bool)
    for _ in range(max_steps):
        if done.all():
            break
        with torch.no_grad():
            tips_t, jac_t = hand.fingertip_jacobians(*pose.tensors())
        tips, jac = tips_t[0].numpy(), jac_t[0].numpy()
        _, grad, _ = cloud.signed_distance(tips)
        touching = _fingertips_touch(hand, pose, cloud)
        delta = np.zeros(n)
        for i in np.flatnonzero(~done):
            if touching[i]:
                done[i] = True
                continue
            cols = np.flatnonzero(np.abs(jac[i, :, 6:]).sum(axis=0) > 1e-9) + 6
            g = grad[i] @ jac[i][:, cols]  # dΦ/dq of this finger's joints
            if np.linalg.norm(g) < 1e-9:
                done[i] = True
                continue
            step = -g / np.linalg.norm(g) * 0.05
            delta[cols] += step
        new_q = np.clip(pose.q + delta[6:], lower, upper)
        if np.allclose(new_q, pose.q):
            break
        delta[6:] = new_q - pose.q
        pose = pose.step(hand, delta)
    return pose, time.perf_counter() - t0
