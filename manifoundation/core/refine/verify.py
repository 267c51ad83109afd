"""Verification of a hand pose on exact geometry (docs/evaluation.md), shared by refinement and the baseline.


Nothing here is judged on the optimiser's proxies (collision spheres, the sampled contact surface's distances):

- contacts: each fingertip's contact sample (`manifoundation.core.refine.contact`) gives the place; the contact point is
the
  object's surface point nearest to it — on the sent mesh (exact closest point) or, without a mesh, on the oriented
  points' surface (`PointCloudField`, which keeps concavities; never a convex hull);
- tip distance: the exact distance from each contact point to the posed fingertip body's collision mesh
  (`manifoundation.core.geometry.closest`): the contact lies on the object by construction and must lie on the finger
  within 5 mm; with a region mask it must also lie within 5 mm of an allowed point;
- friction cones and the wrench use the object's normals as given: the caller's normal of the point nearest the
  contact (as the refinement has them; an outside check uses the same) — never a re-estimated or smoothed one;
  forces solve Eq. (6-8) (normal components ≥ 0 by the cones),
  residual ‖R Σ G_i f_i − τ‖² < 1e-6 for the unit target; for force closure Ferrari–Canny ε > 0 (parallel-jaw
  grippers: soft-finger pads);
- hand–object penetration ≤ 1 mm on the hand's collision meshes against the mesh (fcl + exact signed distance) or
  the points' surface grown by its resolution, ≤ 0.5 mm there (the true surface may reach that far beyond the
  points: a block's corner between samples poked 1.4 mm into a finger); self-collision depth ≤ 1 mm on the meshes
  (`manifoundation.core.geometry`).

``geometry`` says which object surface was used: ``"mesh"`` or ``"points"``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from manifoundation.core.geometry.closest import mesh_triangles
from manifoundation.core.geometry.link_poses import link_poses_at
from manifoundation.core.refine.closure import ferrari_canny
from manifoundation.core.refine.contact import surface_contacts
from manifoundation.core.refine.field import PointCloudField
from manifoundation.core.refine.forces import DEFAULT_MAX_NORMAL_FORCE, ForceSolution, solve_forces
from manifoundation.core.refine.state import HandPose
from manifoundation.core.refine.wrench import WrenchTask

if TYPE_CHECKING:
    from manifoundation.core.robots.hand import Hand

RESIDUAL_SQ_TOL = 1e-6
TIP_TOL = 4e-3
PENETRATION_TOL = 1e-3
POINTS_PENETRATION_TOL = 5e-4
"""m: without a mesh, against the points' surface grown by its resolution — the refinement's own bound: a
cabinet's sharp edge reached 2.5 mm beyond its points, and 1 mm here let a 1.03 mm overlap through."""
SELF_COLLISION_TOL = 1e-3
PAD_TORSION = 0.005  # m: soft-finger torsional coefficient used for two-fingertip (parallel-jaw) hands


@dataclass
class Verification:
    """Measured quality of a final pose and whether it passes (``failures`` names the criteria it misses).

    ``epsilon`` is the Ferrari–Canny ε for force-closure tasks, NaN (not measured) for the others."""

    residual_norm: float
    max_tip_distance: float
    penetration: float
    self_collision: float
    epsilon: float
    forces: np.ndarray
    tips: np.ndarray
    contacts: np.ndarray
    normals: np.ndarray
    geometry: str = "points"
    links: list[str] = field(default_factory=list)
    finger_distances: np.ndarray = field(default_factory=lambda: np.zeros(0))
    failures: list[str] = field(default_factory=list)
    complete: bool = True
    """False: stopped at the contact tests' failure (``complete=False`` in `verify`); penetration and
    self-collision not measured (NaN), for force closure ε neither where the wrench fails (−inf), ``failures``
    the contact tests' only."""

    @property
    def success(self) -> bool:
        return not self.failures


def torsion_for(hand: Hand) -> float:
    """Soft-finger coefficient for the closure metric: pads for two-fingertip grippers, point contacts else."""
    return PAD_TORSION if hand.num_fingertips == 2 else 0.0


def produces_wrench(sol: ForceSolution) -> bool:
    """Verification's wrench test of optimal forces: their squared residual below `RESIDUAL_SQ_TOL`."""
    return bool(sol.residual_norm**2 < RESIDUAL_SQ_TOL)


def contact_quality(
    hand: Hand, contacts: np.ndarray, normals: np.ndarray, task: WrenchTask, mu: float | np.ndarray,
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
    hand: Hand,
    pose: HandPose,
    cloud: PointCloudField,
    task: WrenchTask,
    mu: float,
    mesh: Any | None = None,
    max_normal_force: float = DEFAULT_MAX_NORMAL_FORCE,
    collisions: bool = True,
    complete: bool = True,
    given: np.ndarray | None = None,
) -> Verification:
    """Verify ``pose`` (see module doc).

    Args:
        hand: a `manifoundation.core.robots.Hand`.
        pose: final pose.
        cloud: the object's oriented points (and region mask, if any).
        task: the task the forces must produce.
        mu: friction coefficient.
        mesh: the object's watertight trimesh (exact distances and penetration); None: the points' surface.
        max_normal_force: force bound of Eq. (6-8).
        collisions: measure penetration and self-collision with fcl (False: skip, reported as 0).
        complete: False stops once the wrench or tip-distance test fails (a pass or fail is all the caller needs:
            the refinement asking whether to stop) — the same verdict, without the collision tests.
        given: (H, 3) the caller's contacts, H ≤ fingertips: only the H fingertips nearest them (one each, least
            total distance) are contacts, in ``given``'s order; the others touch nothing the answer counts on
            (zero force). None: every fingertip.
    """
    region = cloud.region_distance if cloud.mask is not None else None
    found = surface_contacts(hand, pose.tensors(), cloud, region, jacobian=False, guards=False)
    samples = found.points
    contacts = mesh_triangles(mesh).closest(samples)[0] if mesh is not None else found.object_points(cloud)
    contacts = np.asarray(contacts, dtype=np.float64)
    finger = finger_surface_distances(hand, pose, contacts)
    links = [str(hand.contact_surface.link[k]) or hand.fingertip_links[i] for i, k in enumerate(found.sample)]
    if given is not None:
        keep = nearest_fingertips(contacts, given)
        samples, contacts, finger, links = samples[keep], contacts[keep], finger[keep], [links[i] for i in keep]
    normals = cloud.given_normal(contacts)
    tip_dist = finger.copy()
    if cloud.mask is not None:
        tip_dist = np.maximum(tip_dist, cloud.region_point_distance(contacts))
    if task.closure:  # (incomplete: no ε where the wrench already fails)
        sol, eps = contact_quality(hand, contacts, normals, task, mu, max_normal_force,
                                   epsilon_below=None if complete else RESIDUAL_SQ_TOL)  # fmt: skip
    else:  # ε only judges force closure (≈ 10 ms, as much as the rest of the contact tests): not measured
        sol, eps = solve_forces(task, contacts, normals, mu, max_normal_force), float("nan")
    failures = [] if produces_wrench(sol) else ["wrench_residual"]
    if not float(np.max(tip_dist)) <= TIP_TOL:
        failures.append("tip_distance")
    pen = selfc = 0.0
    if failures and not complete:
        pen = selfc = float("nan")
    elif collisions:
        from manifoundation.core.geometry import hand_field_penetration, hand_mesh_penetration, hand_self_collision

        if mesh is not None:
            pen = hand_mesh_penetration(hand, mesh, cloud.points, pose.palm_pos, pose.palm_quat, pose.q)
        else:
            pen = hand_field_penetration(hand, cloud, pose.palm_pos, pose.palm_quat, pose.q,
                                         inflate=cloud.resolution)  # fmt: skip
        selfc = hand_self_collision(hand, pose.palm_pos, pose.palm_quat, pose.q)
    if pen > (PENETRATION_TOL if mesh is not None else POINTS_PENETRATION_TOL):
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
        tips=samples,
        contacts=contacts,
        normals=np.asarray(normals, dtype=np.float64),
        geometry="mesh" if mesh is not None else "points",
        links=links,
        finger_distances=finger,
        failures=failures,
        complete=complete or not failures,
    )


def nearest_fingertips(contacts: np.ndarray, given: np.ndarray) -> np.ndarray:
    """Indices (H,) of the fingertip contacts (m, 3) that serve the given points (H, 3), H ≤ m: one fingertip each,
    the least total distance (Hungarian assignment), in ``given``'s order."""
    from scipy.optimize import linear_sum_assignment

    given = np.asarray(given, dtype=np.float64).reshape(-1, 3)
    cost = np.linalg.norm(given[:, None, :] - contacts[None, :, :], axis=2)
    rows, cols = linear_sum_assignment(cost)
    return np.asarray(cols[np.argsort(rows)], dtype=np.int64)


def finger_surface_distances(hand: Hand, pose: HandPose, points: np.ndarray) -> np.ndarray:
    """Exact distance (m,) from each contact point (m, 3) to its posed fingertip body's collision mesh."""
    poses = link_poses_at(hand, pose.palm_pos, pose.palm_quat, pose.q)
    out = np.zeros(len(points))
    for i, body in enumerate(hand.fingertip_bodies):
        T = poses[body]
        local = (points[i] - T[:3, 3]) @ T[:3, :3]
        mesh = hand.collision_meshes.get(body)
        if mesh is not None and len(mesh.faces):
            out[i] = float(mesh_triangles(mesh).closest(local[None])[1][0])
        else:
            out[i] = np.inf
    return out
