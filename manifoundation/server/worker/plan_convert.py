"""Wire ↔ science for plans: `PlanRequest` → `manifoundation.core.planning.PlanInput`, `PlanOutput` → `PlanResult`.

Field for field (the science's names are the wire's, `docs/planning.md`); each step's proposal goes through the
single request's conversion (`manifoundation.server.worker.convert.to_proposal`), with the hand's collision spheres at
its pose for the viewer. Imported in the worker process only (it imports `models`, hence torch).
"""

from __future__ import annotations

import time
from typing import TYPE_CHECKING

import numpy as np

from manifoundation.contract import (
    BoxObstacleIn,
    MeshObstacleIn,
    ObstacleIn,
    PlanRequest,
    PlanResult,
    PlanStep,
    PoseIn,
    SegmentReport,
    WaypointRepair,
)
from manifoundation.core.planning import (
    BoxObstacle,
    MeshObstacle,
    Obstacle,
    PlanInput,
    PlanOptions,
    PlanOutput,
    PointCloudObstacle,
    Pose,
    SupportPlane,
)
from manifoundation.server.worker.convert import to_proposal

if TYPE_CHECKING:
    from manifoundation.core.robots.hand import Hand


def pose_of(pose: PoseIn) -> Pose:
    """The science's pose of a wire pose (the quaternion is already unit: the contract normalised it)."""
    return Pose(np.asarray(pose.position, dtype=np.float64), np.asarray(pose.quaternion, dtype=np.float64))


def pose_in(pose: Pose) -> PoseIn:
    """The wire pose of a science pose."""
    return PoseIn(position=np.asarray(pose.position, np.float64), quaternion=np.asarray(pose.quaternion, np.float64))


def obstacle_of(obstacle: ObstacleIn) -> Obstacle:
    """The science's obstacle of a wire one (same kinds, same fields)."""
    name = obstacle.name or ""
    if isinstance(obstacle, BoxObstacleIn):
        return BoxObstacle(np.asarray(obstacle.size, np.float64), pose_of(obstacle.pose), name)
    if isinstance(obstacle, MeshObstacleIn):
        return MeshObstacle(np.asarray(obstacle.vertices, np.float64), np.asarray(obstacle.faces, np.int64),
                            pose_of(obstacle.pose), name)  # fmt: skip
    return PointCloudObstacle(np.asarray(obstacle.points, np.float64), float(obstacle.resolution), name)


def to_plan_input(request: PlanRequest, hand: Hand, deadline: float | None = None) -> PlanInput:
    """The core input of ``request`` for ``hand``.

    Args:
        deadline: Unix time after which no step is synthesised any more (the rest are answered failed); the
            plan's own budget, ``options.timeout`` from now, applies too, whichever comes first.
    """
    obj, opt, scene = request.object, request.options, request.scene
    budget = time.time() + opt.timeout
    end = budget if deadline is None else min(deadline, budget)
    plane = scene.support_plane
    options = PlanOptions(
        time_limit=opt.time_limit, translation_step=opt.translation_step, rotation_step=opt.rotation_step,
        seed=opt.seed, repair=opt.repair.value, max_repair_distance=opt.max_repair_distance, contacts=opt.contacts,
        method=opt.method.value, num_proposals=opt.num_proposals, max_iterations=opt.max_iterations,
        max_contact_shift=opt.max_contact_shift, deadline=time.monotonic() + (end - time.time()),
    )  # fmt: skip
    return PlanInput(
        points=obj.points.astype(np.float64),
        hand=hand,
        start=pose_of(request.start),
        waypoints=[pose_of(w) for w in request.waypoints],
        obstacles=[obstacle_of(o) for o in scene.obstacles],
        support=None if plane is None else SupportPlane(float(plane.height), float(plane.tolerance)),
        normals=None if obj.normals is None else obj.normals.astype(np.float64),
        mesh_vertices=None if obj.mesh is None else obj.mesh.vertices,
        mesh_faces=None if obj.mesh is None else obj.mesh.faces,
        properties=obj.properties.present(),
        mask=None if obj.region_mask is None else obj.region_mask.astype(bool),
        options=options,
        hand_key=hand.name,
    )


def to_plan_result(out: PlanOutput, request: PlanRequest, hand: Hand, model_version: str) -> PlanResult:
    """The wire answer of a plan: poses (T, 3) + (T, 4), repairs, segments, and every step's proposal as a single
    request's (with the hand's spheres at its pose; its meshes when ``options.return_hand_mesh``)."""
    mesh = request.options.return_hand_mesh
    steps = [
        PlanStep(
            index=s.index, grasp=s.grasp, success=s.success, contact_shift=float(s.contact_shift),
            hand_collisions=list(s.hand_collisions), dropped=s.dropped, seconds=float(s.seconds), calls=s.calls,
            proposal=None if s.proposal is None else to_proposal(s.proposal, hand, mesh=mesh),
        )
        for s in out.steps
    ]
    return PlanResult(
        success=out.success,
        positions=np.array([p.position for p in out.poses], dtype=np.float64).reshape(-1, 3),
        quaternions=np.array([p.quaternion for p in out.poses], dtype=np.float64).reshape(-1, 4),
        waypoint_indices=list(out.waypoint_indices),
        repairs=[WaypointRepair(index=r.index, requested=pose_in(r.requested), repaired=pose_in(r.repaired),
                                distance=float(r.distance), obstacles=list(r.obstacles)) for r in out.repairs],
        segments=[SegmentReport(index=g.index, straight=g.straight, planner_seconds=g.planner_seconds,
                                simplify_seconds=g.simplify_seconds, raw_states=g.raw_states,
                                simplified_states=g.simplified_states, dense_steps=g.dense_steps)
                  for g in out.segments],
        steps=steps,
        regrasps=out.regrasps,
        kept_share=float(out.kept_share),
        hand=request.robot.name or hand.name,
        model_version=model_version,
        timings={k: float(v) for k, v in out.timings.items()},
    )  # fmt: skip
