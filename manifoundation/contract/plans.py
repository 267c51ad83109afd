"""A manipulation plan (``POST /v1/plans``): the object, its start pose, sparse waypoints and the scene
in; the dense collision-free trajectory, the repaired waypoints and a contact answer per step out.

Frames: the object's points, normals and mesh are in the object's own frame; ``start`` and the ``waypoints`` place
that frame in the world. Everything answered is in the world frame (each step's contacts and hand pose with the
object at that step's first pose). Units and encodings as in every request: metres, seconds, radians,
quaternions (w, x, y, z) normalised on input, arrays as nested lists in JSON and typed binary in msgpack.
"""

from __future__ import annotations

from enum import StrEnum
from typing import Annotated, Literal

import numpy as np
from pydantic import Field, model_validator

from manifoundation.contract.arrays import spec
from manifoundation.contract.common import Faces, Quaternion, Rows3, Vec3, WireModel
from manifoundation.contract.objects import Material, ObjectIn
from manifoundation.contract.requests import MAX_PROPOSALS, MAX_TIMEOUT_S
from manifoundation.contract.results import Proposal
from manifoundation.contract.robots import RobotIn

MAX_WAYPOINTS = 64
MAX_OBSTACLES = 64
MAX_OBSTACLE_POINTS = 200_000


class PoseIn(WireModel):
    """A rigid pose: ``position`` (m) and ``quaternion`` (w, x, y, z; normalised on input)."""

    position: Vec3
    quaternion: Quaternion = Field(default_factory=lambda: np.array([1.0, 0.0, 0.0, 0.0]))


def _identity() -> PoseIn:
    return PoseIn(position=np.zeros(3))


class BoxObstacleIn(WireModel):
    """A solid box of full extents ``size`` (m) centred on ``pose``."""

    kind: Literal["box"] = "box"
    name: str | None = Field(None, max_length=64, description="Cited in repairs and collisions.")
    size: Vec3
    pose: PoseIn = Field(default_factory=_identity)

    @model_validator(mode="after")
    def _positive(self) -> BoxObstacleIn:
        if np.any(self.size <= 0):
            raise ValueError("size: every extent must be > 0")
        return self


class MeshObstacleIn(WireModel):
    """A triangle mesh in its own frame, placed by ``pose`` (a closed mesh also holds what is inside it)."""

    kind: Literal["mesh"] = "mesh"
    name: str | None = Field(None, max_length=64)
    vertices: Rows3
    faces: Faces
    pose: PoseIn = Field(default_factory=_identity)

    @model_validator(mode="after")
    def _faces_index_vertices(self) -> MeshObstacleIn:
        if len(self.faces) == 0 or self.faces.min() < 0 or self.faces.max() >= len(self.vertices):
            raise ValueError(f"faces: need ≥ 1 face indexing vertices 0..{len(self.vertices) - 1}")
        return self


class PointCloudObstacleIn(WireModel):
    """Points sensed on obstacles (world frame); the voxels of side ``resolution`` that hold a point collide."""

    kind: Literal["points"] = "points"
    name: str | None = Field(None, max_length=64)
    points: Annotated[np.ndarray, spec("P", 3)] = Field(..., json_schema_extra={"maxItems": MAX_OBSTACLE_POINTS})
    resolution: float = Field(0.01, gt=0, le=0.5, description="Voxel side, m.")

    @model_validator(mode="after")
    def _size(self) -> PointCloudObstacleIn:
        if not 1 <= len(self.points) <= MAX_OBSTACLE_POINTS:
            raise ValueError(f"points: {len(self.points)} given, need 1..{MAX_OBSTACLE_POINTS}")
        return self


ObstacleIn = Annotated[BoxObstacleIn | MeshObstacleIn | PointCloudObstacleIn, Field(discriminator="kind")]


class SupportPlaneIn(WireModel):
    """A table: the plane z = ``height`` (world, z up), free space above; bodies may reach ``tolerance`` below."""

    height: float = 0.0
    tolerance: float = Field(0.001, ge=0, le=0.05, description="m the object (resting on it) may reach below.")


class SceneIn(WireModel):
    """The obstacles around the object, and an optional support plane."""

    obstacles: list[ObstacleIn] = Field(default_factory=list, max_length=MAX_OBSTACLES)
    support_plane: SupportPlaneIn | None = None


class RepairMode(StrEnum):
    """What to do with a waypoint where the object would collide."""

    NEAREST = "nearest"  # move it to the nearest collision-free position, same orientation
    REPORT = "report"  # answer an error naming the waypoint


class PlanMethod(StrEnum):
    """Where a new grasp's contacts come from."""

    NETWORK = "network"
    RANDOM_CONTACTS = "random_contacts"


class PlanOptions(WireModel):
    """How to plan and synthesise."""

    time_limit: float = Field(5.0, gt=0, le=600, description="RRT-Connect seconds over all segments.")
    translation_step: float = Field(0.02, gt=0, le=1.0, description="Largest translation of one step, m.")
    rotation_step: float = Field(0.2, gt=0, le=np.pi, description="Largest rotation of one step, rad.")
    seed: int = Field(0, ge=0, le=2**31 - 1, description="Seeds planner and synthesis; same seed, same plan.")
    repair: RepairMode = RepairMode.NEAREST
    max_repair_distance: float = Field(0.10, gt=0, le=2.0, description="How far a waypoint may be moved, m.")
    contacts: bool = Field(True, description="Synthesise contacts for every step (off: the trajectory only).")
    method: PlanMethod = PlanMethod.NETWORK
    num_proposals: int = Field(4, ge=1, le=MAX_PROPOSALS, description="Hand proposals per new grasp.")
    max_iterations: int = Field(100, ge=1, le=500)
    max_contact_shift: float = Field(0.01, gt=0, le=1.0, description="A grasp is kept while its contacts move "
                                     "at most this far on the object, m.")  # fmt: skip
    timeout: float = Field(120.0, gt=0, le=MAX_TIMEOUT_S, description="The plan's compute budget, s: steps not "
                           "synthesised by then are answered failed.")  # fmt: skip
    return_hand_mesh: bool = Field(False, description="Each step's hand as posed collision meshes (large).")


class PlanRequest(WireModel):
    """Body of ``POST /v1/plans``."""

    object: ObjectIn
    start: PoseIn
    waypoints: list[PoseIn] = Field(..., min_length=1, max_length=MAX_WAYPOINTS)
    scene: SceneIn = Field(default_factory=SceneIn)
    robot: RobotIn
    options: PlanOptions = Field(default_factory=PlanOptions)

    @model_validator(mode="after")
    def _rigid(self) -> PlanRequest:
        if self.object.material is not Material.RIGID:
            raise ValueError(f"object.material: a plan carries the object rigidly, not '{self.object.material}'")
        return self


class WaypointRepair(WireModel):
    """A waypoint that was moved out of collision."""

    index: int = Field(..., ge=0, description="Position in the request's waypoints.")
    requested: PoseIn
    repaired: PoseIn
    distance: float = Field(..., ge=0, description="How far it moved, m.")
    obstacles: list[str] = Field(..., description="What the requested pose collided with ('support_plane').")


class SegmentReport(WireModel):
    """How one segment (waypoint i − 1, or the start, to waypoint i) was planned."""

    index: int = Field(..., ge=0)
    straight: bool = Field(..., description="The straight motion was free: no planner call.")
    planner_seconds: float = Field(..., ge=0)
    simplify_seconds: float = Field(..., ge=0)
    raw_states: int = Field(..., ge=0)
    simplified_states: int = Field(..., ge=0)
    dense_steps: int = Field(..., ge=0)


class GraspChange(StrEnum):
    """What the hand does at a step."""

    NEW = "new"  # the first grasp, or one after a failed step
    KEPT = "kept"  # the previous step's grasp, carried with the object, still produces the wrench
    REGRASP = "regrasp"  # it did not: a new grasp is taken here
    FAILED = "failed"  # no verified, collision-free hand was found


class PlanStep(WireModel):
    """The contact answer of step k: the object moves from ``positions[k]`` to ``positions[k + 1]``."""

    index: int = Field(..., ge=0)
    grasp: GraspChange
    success: bool = Field(..., description="Verified like a single request and the hand is collision-free.")
    proposal: Proposal | None = None
    contact_shift: float = Field(0.0, ge=0, description="Largest move of a contact on the object since the "
                                 "previous step, m.")  # fmt: skip
    hand_collisions: list[str] = Field(default_factory=list)
    dropped: str = Field("", description="Why the previous grasp was not kept.")
    seconds: float = Field(0.0, ge=0, description="Synthesis time of this step.")
    calls: int = Field(0, ge=0, description="Synthesis calls the step took.")


class PlanResult(WireModel):
    """The answer: T dense poses (``positions`` (T, 3), ``quaternions`` (T, 4)) and T − 1 steps."""

    success: bool = Field(..., description="Every step verified and collision-free.")
    positions: Annotated[np.ndarray, spec("T", 3)]
    quaternions: Annotated[np.ndarray, spec("T", 4)]
    waypoint_indices: list[int] = Field(..., description="Index in the poses of each (repaired) waypoint.")
    repairs: list[WaypointRepair] = Field(default_factory=list)
    segments: list[SegmentReport] = Field(default_factory=list)
    steps: list[PlanStep] = Field(default_factory=list)
    regrasps: list[int] = Field(default_factory=list, description="Steps where a new grasp replaces a held one.")
    kept_share: float = Field(1.0, ge=0, le=1, description="Share of the steps after the first that keep the grasp.")
    hand: str
    model_version: str | None = None
    timings: dict[str, float] = Field(default_factory=dict, description="Seconds per stage.")

    @model_validator(mode="after")
    def _consistent(self) -> PlanResult:
        if len(self.positions) != len(self.quaternions):
            raise ValueError("quaternions: one per position")
        if self.steps and len(self.steps) != len(self.positions) - 1:
            raise ValueError(f"steps: {len(self.steps)} given for {len(self.positions)} poses (need T − 1)")
        return self
