"""The object's dense collision-free trajectory through its waypoints: check the start, repair (or report) the
waypoints, plan each segment (`manifoundation.core.planning.planner`), densify (`manifoundation.core.planning.densify`),
and check every
dense pose once more."""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from manifoundation.core.planning.densify import densify
from manifoundation.core.planning.planner import SegmentPlanner, ompl_seed
from manifoundation.core.planning.poses import Pose
from manifoundation.core.planning.repair import nearest_free
from manifoundation.core.planning.scene import CollisionScene
from manifoundation.core.planning.types import (
    InfeasibleWaypoint,
    NoPathFound,
    PlanOptions,
    Progress,
    SegmentReport,
    WaypointRepair,
)


@dataclass
class Trajectory:
    """Dense poses, each waypoint's index among them, the repairs, per-segment reports and seconds per stage."""

    poses: list[Pose]
    waypoint_indices: list[int]
    repairs: list[WaypointRepair]
    segments: list[SegmentReport]
    timings: dict[str, float]


def repair_waypoints(
    scene: CollisionScene, start: Pose, waypoints: list[Pose], options: PlanOptions
) -> tuple[list[Pose], list[WaypointRepair]]:
    """The waypoints with those in collision moved (``repair="nearest"``) or reported.

    Raises:
        InfeasibleWaypoint: the start collides; or a waypoint does and ``repair="report"``, or no free position
            lies within ``max_repair_distance``.
    """
    hits = scene.object_hits(start)
    if hits:
        raise InfeasibleWaypoint("start", hits, "the object's start pose is in collision")
    out, repairs = [], []

    def free(p: Pose) -> bool:
        return not scene.object_hits(p)

    for i, w in enumerate(waypoints):
        hits = scene.object_hits(w)
        if not hits:
            out.append(w)
            continue
        name = f"waypoints[{i}]"
        if options.repair == "report":
            raise InfeasibleWaypoint(name, hits, "the object is in collision there (options.repair is 'report')")
        fixed = nearest_free(w, free, options.max_repair_distance, step=min(0.005, options.max_repair_distance))
        if fixed is None:
            raise InfeasibleWaypoint(
                name, hits, f"no collision-free position within {options.max_repair_distance} m at this orientation"
            )
        repairs.append(WaypointRepair(i, w, fixed, w.translation_to(fixed), hits))
        out.append(fixed)
    return out, repairs


def plan_trajectory(
    scene: CollisionScene, start: Pose, waypoints: list[Pose], options: PlanOptions, progress: Progress | None = None
) -> Trajectory:
    """Plan start → waypoints[0] → … → waypoints[-1] (see module doc).

    Raises:
        InfeasibleWaypoint: see `repair_waypoints`. NoPathFound: a segment RRT-Connect could not connect in time.
    """
    report = progress or (lambda stage, completed, total: None)
    t0 = time.perf_counter()
    report("repair", 0, len(waypoints))
    targets, repairs = repair_waypoints(scene, start, waypoints, options)
    report("repair", len(waypoints), len(waypoints))
    timings = {"repair": time.perf_counter() - t0}
    ends = [start, *targets]
    names = ["start", *(f"waypoints[{i}]" for i in range(len(targets)))]
    positions = np.array([p.position for p in ends])
    planner = SegmentPlanner(
        scene.object_free, positions.min(0) - options.workspace_margin, positions.max(0) + options.workspace_margin,
        scene.object_radius, options.collision_resolution,
    )
    t0 = time.perf_counter()
    poses, indices, segments = [start], [], []
    spent = 0.0
    report("planning", 0, len(targets))
    for i in range(len(targets)):
        budget = (options.time_limit - spent) / (len(targets) - i)
        path = planner.plan(ends[i], ends[i + 1], max(budget, 1e-3), ompl_seed(options.seed, i))
        spent += path.planner_seconds
        if not path.solved:
            raise NoPathFound(i, names[i], names[i + 1], path.planner_seconds)
        dense = densify(path.poses, options.translation_step, options.rotation_step)
        poses.extend(dense[1:])
        indices.append(len(poses) - 1)
        segments.append(SegmentReport(i, path.straight, path.planner_seconds, path.simplify_seconds,
                                      path.raw_states, len(path.poses), len(dense) - 1))  # fmt: skip
        report("planning", i + 1, len(targets))
    timings["planning"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    for k, pose in enumerate(poses):
        if not scene.object_free(pose):  # a pose between two of the planner's checks along a motion
            seg = _segment_of(k, indices)
            raise NoPathFound(seg, names[seg], names[seg + 1], spent)
    timings["densify"] = time.perf_counter() - t0
    return Trajectory(poses, indices, repairs, segments, timings)


def _segment_of(pose_index: int, waypoint_indices: list[int]) -> int:
    return next(i for i, end in enumerate(waypoint_indices) if pose_index <= end)
