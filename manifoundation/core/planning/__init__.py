"""Planning a manipulation: sparse object waypoints (e.g. from an LLM task planner) and a scene → a dense
collision-free SE(3) trajectory (OMPL RRT-Connect, python-fcl) → the contact answer of every step, keeping the
grasp while it works.

Pure: numpy arrays, poses and a `manifoundation.core.robots.Hand` in, dataclasses out; never imports clients, service or
workers. Modules: `poses` (SE(3) poses), `obstacles` (boxes, meshes, point clouds, support plane), `scene` (the
fcl world of object and hand), `repair` (nearest free waypoint), `planner` (RRT-Connect per segment),
`densify`, `trajectory` (all segments), `grasps` (contacts per step), `plan` (the entry point), `validate`,
`spec` (plan files), `view` (a plotly figure).
"""

from manifoundation.core.planning.obstacles import BoxObstacle, MeshObstacle, Obstacle, PointCloudObstacle, SupportPlane
from manifoundation.core.planning.plan import plan_manipulation, scene_of
from manifoundation.core.planning.poses import IDENTITY, Pose
from manifoundation.core.planning.types import (
    InfeasibleWaypoint,
    InvalidPlan,
    NoPathFound,
    PlanInput,
    PlanningError,
    PlanOptions,
    PlanOutput,
    PlanStep,
    SegmentReport,
    WaypointRepair,
)

__all__ = [
    "IDENTITY",
    "BoxObstacle",
    "InfeasibleWaypoint",
    "InvalidPlan",
    "MeshObstacle",
    "NoPathFound",
    "Obstacle",
    "PlanInput",
    "PlanOptions",
    "PlanOutput",
    "PlanStep",
    "PlanningError",
    "PointCloudObstacle",
    "Pose",
    "SegmentReport",
    "SupportPlane",
    "WaypointRepair",
    "plan_manipulation",
    "scene_of",
]
