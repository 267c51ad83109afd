"""Verification of a hand pose with exact geometry (DESIGN.md §5), shared by refinement and the baseline.

Criteria (all must hold): wrench residual ‖R Σ G_i f_i − τ‖² < 1e-6 with the optimal forces of Eq. (6-8) at the
final fingertips (unit target wrench); every fingertip within 5 mm of the surface — a fingertip is its pad sphere
nearest to touching (`models.refine.state.pad_spheres`), its distance is |Φ(centre) − radius| with the exact mesh
signed distance when a mesh is known, else the point field (with a region mask: its contact point within 5 mm of an
allowed point); hand–object penetration ≤ 1 mm and self-collision depth ≤ 1 mm, both measured on the hand's
collision meshes with fcl (`models.geometry`); for force closure, Ferrari–Canny ε > 0 (parallel-jaw grippers:
soft-finger pads).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
import torch

from models.refine.closure import ferrari_canny
from models.refine.field import PointCloudField
from models.refine.forces import DEFAULT_MAX_NORMAL_FORCE, ForceSolution, solve_forces
from models.refine.state import HandPose, contact_points, pad_candidates, select_pads
from models.refine.wrench import WrenchTask

RESIDUAL_SQ_TOL = 1e-6
TIP_TOL = 5e-3
PENETRATION_TOL = 1e-3
SELF_COLLISION_TOL = 1e-3
PAD_TORSION = 0.005  # m: soft-finger torsional coefficient used for two-fingertip (parallel-jaw) hands


@dataclass
class Verification:
    """Measured quality of a final pose and whether it passes (``failures`` names the criteria it misses)."""

    residual_norm: float
    max_tip_distance: float
    penetration: float
    self_collision: float
    epsilon: float
    forces: np.ndarray
    tips: np.ndarray
    contacts: np.ndarray
    normals: np.ndarray
    failures: list[str] = field(default_factory=list)

    @property
    def success(self) -> bool:
        return not self.failures


def torsion_for(hand: Any) -> float:
    """Soft-finger coefficient for the closure metric: pads for two-fingertip grippers, point contacts else."""
    return PAD_TORSION if hand.num_fingertips == 2 else 0.0


def contact_quality(
    hand: Any, contacts: np.ndarray, normals: np.ndarray, task: WrenchTask, mu: float,
    max_normal_force: float = DEFAULT_MAX_NORMAL_FORCE, epsilon_below: float | None = None,
) -> tuple[ForceSolution, float]:
    """The contact-level tests of `verify`: the optimal forces of Eq. (6-8) (their residual is the wrench test)
    and the Ferrari–Canny ε, for contacts (m, 3) with outward normals (m, 3). The grasp sampler's force-closure
    pre-check calls this too, so both judge a grasp the same way. With ``epsilon_below``, ε (≈ 5 ms, 10× the
    force problem) is only computed when the squared residual is below it, else reported as −inf."""
    sol = solve_forces(task, contacts, normals, mu, max_normal_force)
    if epsilon_below is not None and not sol.residual_norm**2 < epsilon_below:
        return sol, -np.inf
    eps = ferrari_canny(contacts, normals, mu, task.centre, task.length, torsional=torsion_for(hand))
    return sol, float(eps)


def verify(
    hand: Any,
    pose: HandPose,
    cloud: PointCloudField,
    task: WrenchTask,
    mu: float,
    mesh: Any | None = None,
    max_normal_force: float = DEFAULT_MAX_NORMAL_FORCE,
    collisions: bool = True,
) -> Verification:
    """Verify ``pose`` (see module doc).

    Args:
        hand: a `models.robots.Hand`.
        pose: final pose.
        cloud: the object's oriented points (and region mask, if any).
        task: the task the forces must produce.
        mu: friction coefficient.
        mesh: the object's watertight trimesh (exact distances and penetration); None: convex hull of the points.
        max_normal_force: force bound of Eq. (6-8).
        collisions: measure penetration and self-collision with fcl (False: skip, reported as 0).
    """
    with torch.no_grad():
        fk_tips = hand.fingertips(*pose.tensors())[0].numpy()
        sph = hand.spheres(*pose.tensors(), jacobian=False)[0][0].numpy()
    region = cloud.region_distance if cloud.mask is not None else None
    tips, _, tip_phi, _ = contact_points(hand, cloud, fk_tips, None, sph, None, region)
    normals = cloud.surface_normal(tips)
    sol, eps = contact_quality(hand, tips, normals, task, mu, max_normal_force)
    if cloud.mask is not None:
        tip_dist = cloud.region_point_distance(tips)
    elif mesh is not None:
        import trimesh

        radius = np.asarray(hand.sphere_radii, dtype=np.float64)
        candidates = pad_candidates(hand)
        gap = np.full(len(radius), np.inf)
        if len(candidates):  # trimesh: positive inside
            gap[candidates] = -trimesh.proximity.signed_distance(mesh, sph[candidates]) - radius[candidates]
        idx = select_pads(hand, gap)
        bare = idx < 0
        tip_dist = np.abs(gap[np.maximum(idx, 0)])
        if bare.any():
            tip_dist[bare] = np.abs(trimesh.proximity.signed_distance(mesh, fk_tips[bare]))
    else:
        tip_dist = np.abs(tip_phi)
    _, _, contacts = cloud.signed_distance(tips)
    pen = selfc = 0.0
    if collisions:
        from models.geometry import ObjectGeometry, hand_object_penetration, hand_self_collision

        geom = ObjectGeometry.from_points(cloud.points, cloud.normals, mesh)
        pen = hand_object_penetration(hand, geom, pose.palm_pos, pose.palm_quat, pose.q)
        selfc = hand_self_collision(hand, pose.palm_pos, pose.palm_quat, pose.q)
    failures = []
    if not sol.residual_norm**2 < RESIDUAL_SQ_TOL:
        failures.append("wrench_residual")
    if not float(np.max(tip_dist)) <= TIP_TOL:
        failures.append("tip_distance")
    if pen > PENETRATION_TOL:
        failures.append("penetration")
    if selfc > SELF_COLLISION_TOL:
        failures.append("self_collision")
    if task.closure and not eps > 0:
        failures.append("not_force_closure")
    return Verification(
        residual_norm=sol.residual_norm,
        max_tip_distance=float(np.max(tip_dist)),
        penetration=float(pen),
        self_collision=float(selfc),
        epsilon=float(eps),
        forces=sol.forces,
        tips=tips,
        contacts=np.asarray(contacts),
        normals=normals,
        failures=failures,
    )
