"""Core request and answer of a manipulation plan (pure dataclasses; the worker will map the wire schemas of
``manifoundation/contract/plans.py`` here, field for field, without this package importing them).

Frames: the object's points, normals and mesh are given in the object's own (body) frame; ``start`` and the
``waypoints`` place that frame in the world. Every answer is in the world frame: the dense poses, and each step's
contacts, forces and hand pose with the object at that step's first pose.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import ClassVar, Literal

import numpy as np

from manifoundation.core.pipeline.types import InvalidInput, ProposalOutput
from manifoundation.core.planning.obstacles import Obstacle, SupportPlane
from manifoundation.core.planning.poses import Pose
from manifoundation.core.robots.hand import Hand

REPAIR_MODES = ("nearest", "report")
GraspChange = Literal["new", "kept", "regrasp", "failed"]
Progress = Callable[[str, int, int], None]
"""progress(stage, completed, total): "repair" (waypoints checked), "planning" (segments), "contacts" (steps)."""


class PlanningError(InvalidInput):
    """Base of the planner's errors. Each is the caller's to fix (a 422 for the route: the message starts with the
    field), so all are `InvalidInput`s."""


class InvalidPlan(PlanningError):
    """A plan request that cannot be processed (the message names the field)."""


class InfeasibleWaypoint(InvalidPlan):
    """A waypoint (or the start) where the object collides with the scene and that was not repaired: with
    ``repair="report"``, or when no collision-free pose lies within ``max_repair_distance``.

    Attributes:
        field: the pose's name, ``"start"`` or ``"waypoints[i]"``.
        obstacles: names of the obstacles the object meets there (``"support_plane"`` for the plane).
    """

    code: ClassVar[str] = "InfeasibleWaypoint"

    def __init__(self, field_name: str, obstacles: list[str], detail: str) -> None:
        super().__init__(f"{field_name}: {detail} (collides with {', '.join(obstacles) or 'the scene'})")
        self.field = field_name
        self.obstacles = obstacles
        self.detail = detail

    def __reduce__(self) -> tuple[type, tuple[str, list[str], str]]:  # picklable across worker processes
        return type(self), (self.field, self.obstacles, self.detail)


class NoPathFound(PlanningError):
    """RRT-Connect found no collision-free motion between two consecutive waypoints within its time.

    Attributes:
        segment: the segment's index (it ends at ``waypoints[segment]``). field: ``"waypoints[segment]"``.
    """

    code: ClassVar[str] = "NoPathFound"

    def __init__(self, segment: int, source: str, target: str, seconds: float) -> None:
        super().__init__(f"waypoints: no collision-free path from {source} to {target} in {seconds:.2f} s "
                         f"(segment {segment}; raise options.time_limit or move the waypoints)")
        self.segment = segment
        self.field = f"waypoints[{segment}]"
        self._args = (segment, source, target, seconds)

    def __reduce__(self) -> tuple[type, tuple[int, str, str, float]]:  # picklable across worker processes
        return type(self), self._args


@dataclass
class PlanOptions:
    """How to plan and synthesise.

    Attributes:
        time_limit: s, RRT-Connect's time over all segments (split evenly over those still to plan).
        translation_step, rotation_step: m and rad: the dense trajectory's largest step (the contact model is
            called once per step).
        seed: seeds the planner (OMPL's RNG, one derived seed per segment) and the synthesis; same seed, same plan.
        repair: ``"nearest"``: a waypoint in collision is moved to the nearest collision-free position (same
            orientation, `manifoundation.core.planning.repair`); ``"report"``: it is an `InfeasibleWaypoint` error.
        max_repair_distance: m, how far a waypoint may be moved.
        collision_resolution: m of SE(3) distance (translation + arc length of the object's farthest point)
            between two collision checks along a motion.
        workspace_margin: m around the start and the waypoints that bounds the planner's sampling box.
        contacts: also synthesise contacts for every step (False: the trajectory only).
        method: contacts of a new grasp: ``"network"`` (needs a predictor) or ``"random_contacts"``.
        num_proposals: hand proposals asked for at each new grasp (the one the scene lets be kept longest wins).
        new_grasp_attempts: synthesis calls (other seeds) before a step without a usable new grasp is "failed".
        max_iterations: refinement cap per synthesis.
        max_contact_shift: m, a grasp counts as kept while its contacts move at most this far on the object.
        lookahead: dense poses over which a new grasp's hand is checked against the scene when choosing it.
        deadline: `time.monotonic()` value after which no further step is synthesised (the rest are "failed").
    """

    time_limit: float = 5.0
    translation_step: float = 0.02
    rotation_step: float = 0.2
    seed: int = 0
    repair: str = "nearest"
    max_repair_distance: float = 0.10
    collision_resolution: float = 0.004
    workspace_margin: float = 0.4
    contacts: bool = True
    method: str = "network"
    num_proposals: int = 4
    new_grasp_attempts: int = 2
    max_iterations: int = 100
    max_contact_shift: float = 0.01
    lookahead: int = 40
    deadline: float | None = None


@dataclass
class PlanInput:
    """One plan request in core form.

    Attributes:
        points: (N, 3) object points, body frame (m). normals: (N, 3) outward unit normals or None (estimated).
        hand: the `manifoundation.core.robots.Hand` that carries the object.
        start: the object's pose now. waypoints: poses it should pass through, in order (the last is the goal).
        obstacles: the scene (`manifoundation.core.planning.scene`). support: a support plane (table), or None.
        mesh_vertices, mesh_faces: the object's mesh, body frame (collision and exact verification); without it
            the planner collides the points' convex hull (a conservative cover) and verification uses the points.
        properties: friction, density (as in a synthesis request). mask: (N,) bool where contact is allowed.
        options: planning and synthesis options. hand_key: the hand's cache key for the network.
    """

    points: np.ndarray
    hand: Hand
    start: Pose
    waypoints: list[Pose]
    obstacles: list[Obstacle] = field(default_factory=list)
    support: SupportPlane | None = None
    normals: np.ndarray | None = None
    mesh_vertices: np.ndarray | None = None
    mesh_faces: np.ndarray | None = None
    properties: dict[str, float] = field(default_factory=dict)
    mask: np.ndarray | None = None
    options: PlanOptions = field(default_factory=PlanOptions)
    hand_key: str | None = None


@dataclass
class WaypointRepair:
    """A waypoint moved out of collision.

    Attributes:
        index: position in ``waypoints``. requested, repaired: the poses before and after. distance: m moved.
        obstacles: what the requested pose collided with.
    """

    index: int
    requested: Pose
    repaired: Pose
    distance: float
    obstacles: list[str]


@dataclass
class SegmentReport:
    """How one segment (between two consecutive waypoints) was planned.

    Attributes:
        index: segment i runs from waypoint i − 1 (the start for i = 0) to waypoint i.
        straight: the straight motion was free, no planner call was needed.
        planner_seconds: RRT-Connect's time; simplify_seconds: path simplification's.
        raw_states, simplified_states: path vertices before and after simplification. dense_steps: steps after
            densification.
    """

    index: int
    straight: bool
    planner_seconds: float
    simplify_seconds: float
    raw_states: int
    simplified_states: int
    dense_steps: int


@dataclass
class PlanStep:
    """The contact answer for step k: the object moves from ``poses[k]`` to ``poses[k + 1]``.

    Attributes:
        index: k.
        proposal: the chosen hand answer (world frame, object at ``poses[k]``), verified like a single request;
            None when nothing was synthesised.
        grasp: ``"new"`` (the first grasp, or one after a failed step), ``"kept"`` (the previous step's hand
            pose, carried with the object, still produces this step's wrench), ``"regrasp"`` (it did not: a new
            grasp was taken here) or ``"failed"`` (no verified, collision-free hand was found).
        contact_shift: m, the largest move of a contact on the object since the previous step (0 for a new grasp).
        hand_collisions: obstacles the chosen hand meets at the step's two poses (empty when free).
        seconds: synthesis time of this step (every pipeline call it took). calls: how many.
        dropped: why the previous grasp was not kept (re-grasp and failed steps after a held grasp), e.g.
            ``"verification: wrench_residual"``, ``"hand meets kettle"``, ``"contacts slid 14.2 mm"``.
    """

    index: int
    proposal: ProposalOutput | None
    grasp: GraspChange
    contact_shift: float = 0.0
    hand_collisions: list[str] = field(default_factory=list)
    seconds: float = 0.0
    calls: int = 0
    dropped: str = ""

    @property
    def success(self) -> bool:
        """The step's answer passed verification and its hand is collision-free with the scene."""
        return self.proposal is not None and self.proposal.quality.success and not self.hand_collisions


@dataclass
class PlanOutput:
    """A plan: the dense collision-free object trajectory and the contact answer of every step.

    Attributes:
        poses: dense object poses (T,), ``poses[0]`` the start, the last the (repaired) final waypoint.
        waypoint_indices: index in ``poses`` of each waypoint.
        repairs: the waypoints that were moved.
        segments: how each segment was planned.
        steps: T − 1 contact answers (empty with ``options.contacts=False``).
        timings: seconds: "repair", "planning", "densify", "contacts", "total".
    """

    poses: list[Pose]
    waypoint_indices: list[int]
    repairs: list[WaypointRepair]
    segments: list[SegmentReport]
    steps: list[PlanStep] = field(default_factory=list)
    timings: dict[str, float] = field(default_factory=dict)

    @property
    def regrasps(self) -> list[int]:
        """Indices of the steps where the hand takes a new grasp after having held one."""
        return [s.index for s in self.steps if s.grasp == "regrasp"]

    @property
    def kept_share(self) -> float:
        """Share of the steps after the first that keep the previous step's grasp."""
        later = self.steps[1:]
        return sum(s.grasp == "kept" for s in later) / len(later) if later else 1.0

    @property
    def success(self) -> bool:
        """Every step has a verified, collision-free answer (the trajectory alone when no contacts were asked)."""
        return all(s.success for s in self.steps)


__all__ = [
    "REPAIR_MODES",
    "GraspChange",
    "InfeasibleWaypoint",
    "InvalidPlan",
    "NoPathFound",
    "PlanInput",
    "PlanOptions",
    "PlanOutput",
    "PlanStep",
    "PlanningError",
    "Progress",
    "SegmentReport",
    "WaypointRepair",
]
