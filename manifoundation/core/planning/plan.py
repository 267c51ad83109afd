"""`plan_manipulation`: sparse object waypoints + a scene → a dense collision-free trajectory with the contact
answer of every step (the science behind ``POST /v1/plans``).

Stages reported to ``progress(stage, completed, total)``: "repair" (the waypoints checked), "planning" (per
segment) and "contacts" (per step).
"""

from __future__ import annotations

import time

from manifoundation.core.pipeline.run import CancelCheck
from manifoundation.core.planning.grasps import synthesise_along
from manifoundation.core.planning.scene import CollisionScene
from manifoundation.core.planning.trajectory import plan_trajectory
from manifoundation.core.planning.types import PlanInput, PlanOutput, Progress
from manifoundation.core.planning.validate import check_plan


def scene_of(inp: PlanInput) -> CollisionScene:
    """The request's collision world: its obstacles and support plane, and the object's collision mesh."""
    return CollisionScene.for_object(inp.obstacles, inp.support, inp.points, inp.mesh_vertices, inp.mesh_faces)


def plan_manipulation(
    inp: PlanInput,
    predictor: object | None = None,
    progress: Progress | None = None,
    should_cancel: CancelCheck | None = None,
) -> PlanOutput:
    """Plan the object's motion through its waypoints and synthesise contacts for every step.

    Args:
        inp: the request in core form.
        predictor: the network (`manifoundation.core.network.ContactPredictor`); required for method "network".
        progress: ``progress(stage, completed, total)`` callback (see module doc).
        should_cancel: polled by every synthesis.

    Returns:
        The plan (steps that found no verified, collision-free hand are returned too, ``grasp="failed"``).

    Raises:
        InvalidPlan: a malformed request (the message names the field). InfeasibleWaypoint: the start, or a
        waypoint that was not repaired, is in collision. NoPathFound: a segment without a path in time.
        ModelUnavailable: method "network" without a predictor. Cancelled: ``should_cancel()`` returned true.
    """
    t_start = time.perf_counter()
    check_plan(inp)
    scene = scene_of(inp)
    traj = plan_trajectory(scene, inp.start, inp.waypoints, inp.options, progress)
    timings = dict(traj.timings)
    steps = []
    if inp.options.contacts:
        t0 = time.perf_counter()
        steps = synthesise_along(inp, scene, traj.poses, predictor, progress, should_cancel)
        timings["contacts"] = time.perf_counter() - t0
    timings["total"] = time.perf_counter() - t_start
    return PlanOutput(traj.poses, traj.waypoint_indices, traj.repairs, traj.segments, steps, timings)
