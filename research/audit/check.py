"""`audit_grasp`: an independent physical check of one grasp proposal.

Criteria (each reported with its measured values; ``passed`` is true when none fails):

* pose: finite values, a unit palm quaternion (±1e-3); the reported joint names are the hand's, reported coupled
  joints agree with the description's couplings, every moving joint below the palm is given or derivable, all
  within their limits (1e-4 slack);
* (a) contact: each contact point lies within ``contact_tol`` of the posed surface of its fingertip link
  (exact point-to-mesh distance; computed in the link's frame, the point moved by ``inv(world_T_link)``, which
  equals the distance to the posed mesh) and within ``contact_tol`` of the object's surface;
* (b) penetration: hand and object overlap by at most ``penetration_tol``, measured both ways on the exact
  meshes (:mod:`research.audit.penetration`);
* (c) friction: each force pushes into the object (normal component ``f·(−n) ≥ 0``) with
  ``tangential ≤ μ · normal`` (relative slack 1e-6); ``n`` is the caller's normal of the nearest given object
  point when ``object_points``/``object_normals`` are given, else the mesh's face normal at the closest point;
* (d) wrench: with ``target_wrench`` ``[F (N), τ (N·m)]``, the cosine between the achieved total wrench and the
  target, both scaled as ``[F, τ / L]``, is at least ``cosine_tol``; with ``closure``, the contacts are in force
  closure (the origin strictly inside the hull of the 8-sided friction pyramids' primitive wrenches).

The centre of the wrenches is ``centre`` if given, else the mesh's centre of mass (its vertex centroid when not
watertight), else the centroid of ``object_points``. ``L`` is ``length`` if given, else the object's
bounding-sphere radius about that centre (the largest distance from the centre to a mesh vertex or point).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
import trimesh
from numpy.typing import ArrayLike
from scipy.spatial import cKDTree

from research.audit.hands import AuditHand, load_hand
from research.audit.penetration import PenetrationAudit, measure_penetration
from research.audit.report import AuditedGrasp, AuditReport, ContactAudit
from research.audit.wrench import closure_epsilon, contact_wrenches, cosine, friction_components, scaled_wrench

FRICTION_SLACK = 1e-6
LIMIT_TOL = 1e-4
QUATERNION_TOL = 1e-3


def _finger_distances(hand: AuditHand, grasp: AuditedGrasp, poses: dict[str, np.ndarray]) -> np.ndarray:
    out = np.full(len(grasp.fingertips), np.inf)
    for link in set(grasp.fingertips):
        if link not in hand.links or link not in poses:
            continue
        idx = [i for i, f in enumerate(grasp.fingertips) if f == link]
        T = poses[link]
        local = (grasp.contact_points[idx] - T[:3, 3]) @ T[:3, :3]
        _, dist, _ = trimesh.proximity.closest_point(hand.links[link].mesh, local)
        out[idx] = dist
    return out


def _centre_and_length(
    mesh: trimesh.Trimesh | None, points: ArrayLike | None, centre: ArrayLike | None, length: float | None
) -> tuple[np.ndarray, float]:
    cloud = np.asarray(mesh.vertices) if mesh is not None else np.asarray(points, dtype=np.float64)
    if centre is None:
        if mesh is not None:
            centre = np.asarray(mesh.center_mass if mesh.is_watertight else cloud.mean(axis=0))
        else:
            centre = cloud.mean(axis=0)
    c = np.asarray(centre, dtype=np.float64)
    return c, float(length) if length is not None else float(np.linalg.norm(cloud - c, axis=1).max())


def audit_grasp(
    hand_name: str | AuditHand,
    grasp: AuditedGrasp,
    object_mesh: trimesh.Trimesh | None,
    object_points: ArrayLike | None = None,
    object_normals: ArrayLike | None = None,
    *,
    mu: float,
    target_wrench: ArrayLike | None = None,
    closure: bool = False,
    soft_finger: float = 0.0,
    contact_tol: float = 5e-3,
    penetration_tol: float = 1e-3,
    cosine_tol: float = 0.99,
    centre: ArrayLike | None = None,
    length: float | None = None,
    sample_spacing: float = 1e-3,
    seed: int = 0,
) -> AuditReport:
    """Audit one grasp against the hand's real geometry and the object's exact surface.

    Args:
        hand_name: a built-in hand name, or an :class:`AuditHand`.
        grasp: the proposal.
        object_mesh: the object in the world frame (watertight for exact penetration); ``None``: distances to
            ``object_points`` only and no penetration check.
        object_points: (N, 3) object surface points (optional; required without a mesh). object_normals: (N, 3) their
        outward normals (with ``object_points``: used for the friction cones). mu: friction coefficient. target_wrench:
        (6,) ``[F (N), τ (N·m)]`` the forces should achieve (optional). closure: also require force closure.
        soft_finger: torsional friction radius (m) of soft-finger contacts for the closure test (rubber pads of a
            parallel gripper resist a moment about the normal; two point contacts are never in closure); 0: point
            contacts.
        contact_tol: contact distance tolerance (m).
        penetration_tol: penetration tolerance (m).
        cosine_tol: least cosine with the target wrench.
        centre: (3,) wrench reference point (default: see the module docstring).
        length: torque scale L (default: the object's bounding-sphere radius about ``centre``).
        sample_spacing: penetration sample spacing (m).
        seed: penetration sampling seed.

    Returns:
        The report.
    """
    hand = load_hand(hand_name) if isinstance(hand_name, str) else hand_name
    if object_mesh is None and (object_points is None or object_normals is None):
        raise ValueError("give an object mesh, or object points with their normals")
    points = np.asarray(grasp.contact_points, dtype=np.float64).reshape(-1, 3)
    forces = np.asarray(grasp.forces, dtype=np.float64).reshape(-1, 3)
    failures: list[str] = []
    notes: list[str] = []
    if len(forces) != len(points) or len(grasp.fingertips) != len(points):
        msg = f"{len(points)} contact points, {len(forces)} forces, {len(grasp.fingertips)} fingertips"
        return AuditReport(False, [msg])
    arrays = (points, forces, grasp.palm_position, grasp.palm_quaternion, grasp.joint_values)
    if not all(np.all(np.isfinite(a)) for a in arrays) or grasp.palm_quaternion.shape != (4,):
        return AuditReport(False, ["non-finite values or a malformed palm pose in the proposal"])
    if abs(float(np.linalg.norm(grasp.palm_quaternion)) - 1.0) > QUATERNION_TOL:
        failures.append(f"palm quaternion is not a unit quaternion (norm {np.linalg.norm(grasp.palm_quaternion):.6g})")
    unknown = sorted({f for f in grasp.fingertips if f not in hand.links})
    if unknown:
        failures.append(f"fingertip links without geometry in {hand.name}: {unknown}")

    q, missing, problems = hand.joint_values(grasp.joint_names, grasp.joint_values)
    failures += problems
    if missing:
        failures.append(f"joints neither reported nor derivable: {missing}")
        return AuditReport(False, failures, notes)
    violations = hand.limit_violations(q, LIMIT_TOL)
    failures += [f"joint {j} outside its limits by {v:.3g}" for j, v in violations.items()]
    poses = hand.link_poses(grasp.palm_position, grasp.palm_quaternion, q)

    # (a) contact distances
    finger = _finger_distances(hand, grasp, poses)
    obj_dist, normals = _object_distances_and_normals(points, object_mesh, object_points, object_normals, notes)
    for k in np.flatnonzero(finger > contact_tol):
        failures.append(f"contact {k} is {finger[k] * 1e3:.2f} mm from {grasp.fingertips[k]}'s surface")
    for k in np.flatnonzero(np.asarray(obj_dist) > contact_tol):
        failures.append(f"contact {k} is {obj_dist[k] * 1e3:.2f} mm from the object surface")

    # (c) friction cones
    contacts = _cone_audits(grasp.fingertips, forces, normals, finger, obj_dist, mu, failures)

    # (d) wrench
    c, L = _centre_and_length(object_mesh, object_points, centre, length)
    if not L > 0.0:
        notes.append(f"degenerate torque scale L = {L}: 1 m used")
        L = 1.0
    wrench = contact_wrenches(points, forces, c, L).sum(axis=0) if len(points) else np.zeros(6)
    report = AuditReport(False, failures, notes, contacts, None, q, violations, wrench, None, None, c, L)
    if target_wrench is not None:
        report.target_cosine = cosine(wrench, scaled_wrench(np.asarray(target_wrench), L))
        if report.target_cosine < cosine_tol:
            failures.append(f"wrench cosine with the target {report.target_cosine:.4f} < {cosine_tol}")
    if closure:
        report.closure_epsilon = closure_epsilon(points, normals, mu, c, L, torsion=soft_finger)
        if report.closure_epsilon <= 0.0:
            failures.append("contacts are not in force closure (linearised cones, 8-sided pyramids)")

    # (b) penetration
    if object_mesh is None:
        notes.append("no object mesh: penetration not measured")
    else:
        report.penetration = _penetration(hand, poses, object_mesh, sample_spacing, seed, penetration_tol, report)
    report.passed = not failures
    return report


def _object_distances_and_normals(
    points: np.ndarray, mesh: trimesh.Trimesh | None, object_points: ArrayLike | None,
    object_normals: ArrayLike | None, notes: list[str],
) -> tuple[np.ndarray, np.ndarray]:
    """(H,) distance of each contact to the object's surface and (H, 3) the outward unit normal there (the
    caller's normals when given, else the mesh's face normals)."""
    normals = np.zeros_like(points)
    if mesh is not None:
        _, obj_dist, tri = trimesh.proximity.closest_point(mesh, points)
        normals = np.asarray(mesh.face_normals)[tri]
    else:
        notes.append("no object mesh: object distances are to the nearest given object point")
        obj_dist, _ = cKDTree(np.asarray(object_points)).query(points)
    if object_points is not None and object_normals is not None:
        _, nearest = cKDTree(np.asarray(object_points, dtype=np.float64)).query(points)
        normals = np.asarray(object_normals, dtype=np.float64)[nearest]
    return np.asarray(obj_dist), normals / np.linalg.norm(normals, axis=1, keepdims=True)


def _cone_audits(
    fingertips: Sequence[str], forces: np.ndarray, normals: np.ndarray, finger: np.ndarray, obj_dist: np.ndarray,
    mu: float, failures: list[str],
) -> list[ContactAudit]:
    """Each contact's force split against its friction cone; a pull or a slip is added to ``failures``."""
    contacts = []
    for i in range(len(forces)):
        fn, ft = friction_components(forces[i], normals[i])
        scale = float(np.linalg.norm(forces[i]))
        ratio = 0.0 if scale == 0.0 else (ft / fn if fn > 0.0 else np.inf)
        contacts.append(ContactAudit(fingertips[i], float(finger[i]), float(obj_dist[i]), normals[i], fn, ft, ratio))
        if fn < -FRICTION_SLACK * scale:
            failures.append(f"contact {i} pulls the object (normal force {fn:.3g} N)")
        elif ft > mu * fn + FRICTION_SLACK * scale:
            failures.append(f"contact {i} leaves its friction cone (tangential/normal {ratio:.3g} > μ = {mu})")
    return contacts


def _penetration(
    hand: AuditHand, poses: dict[str, np.ndarray], mesh: trimesh.Trimesh, spacing: float, seed: int, tol: float,
    report: AuditReport,
) -> PenetrationAudit:
    """The deepest hand-object overlap; an overlap beyond ``tol`` is added to the report's failures."""
    if not mesh.is_watertight:
        report.notes.append("object mesh is not watertight: inside tests on it are approximate")
    pen = measure_penetration(hand.links, poses, mesh, spacing=spacing, seed=seed)
    if pen.hulled_links:
        report.notes.append(f"non-watertight link meshes tested by their convex hulls: {pen.hulled_links}")
    if pen.depth > tol:
        where = np.round(pen.point, 4).tolist() if pen.point is not None else None
        report.failures.append(f"{pen.link} and the object overlap by {pen.depth * 1e3:.2f} mm ({pen.kind} at {where})")
    return pen


def audit_many(
    hand_name: str | AuditHand, grasps: Sequence[AuditedGrasp], object_mesh: trimesh.Trimesh | None, **kwargs: Any
) -> list[AuditReport]:
    """:func:`audit_grasp` for several grasps on one object (same keyword arguments)."""
    return [audit_grasp(hand_name, g, object_mesh, **kwargs) for g in grasps]
