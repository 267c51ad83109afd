"""What the service answers: hand proposals with contacts, forces, pose and quality figures."""

from __future__ import annotations

from typing import Annotated, Literal

import numpy as np
from pydantic import Field, field_validator

from manifoundation.contract.arrays import spec
from manifoundation.contract.common import PerPoint, Points, Quaternion, Rows3, Vec3, Vector, WireModel


class PhysicsTrial(WireModel):
    """One push of the simulated grasp test: the force's direction and how far the object moved and turned."""

    direction: str = Field(..., description="Where the external force pushed: -x, +x, -y, +y, -z or +z (world).")
    translation: float = Field(..., ge=0, description="How far the object's centre of mass moved, m.")
    rotation: float = Field(..., ge=0, description="How far the object turned, degrees.")
    held: bool = Field(..., description="Moved < 5 cm and turned < 15°.")


class PhysicsMotion(WireModel):
    """The target-motion trial of the simulated test (``delta_pose`` tasks): where the object ended."""

    translation_error: float = Field(..., ge=0, description="Distance of the object's centre of mass from the "
                                     "target's at the end, m (success < 1 cm).")
    rotation_error: float = Field(..., ge=0, description="Angle of the object's orientation from the target's at "
                                  "the end, degrees (success < 10°).")
    dropped: bool = Field(..., description="No hand body touched the object at the end.")
    reached: bool = Field(..., description="Ended within 1 cm and 10° of the target pose, not dropped.")


class PhysicsQuality(WireModel):
    """The simulated grasp test (``options.simulate``: unset, each returned proposal; true, a search; MuJoCo,
    DexGraspBench's protocol, docs/physics.md)."""

    held: bool = Field(..., description="The test passed: the object held in all six directions (closure) or "
                       "reached the target pose (motion).")
    reason: str = Field(..., description="held, moved (a push moved or turned it too far), unstable (the "
                        "simulation diverged under both of MuJoCo's solvers: a failure) or penetration (the pregrasp "
                        "penetrates more than 1 cm); motion: reached, missed, dropped or unstable.")
    test: Literal["closure", "motion"] = Field("closure", description="Which test ran: closure (six pushes, gravity "
                                               "off; force_closure and wrench tasks) or motion (delta_pose: the "
                                               "palm carried along the task's motion under gravity).")
    trials: list[PhysicsTrial] = Field(default_factory=list, description="The six pushes (closure; none after "
                                       "penetration).")
    motion: PhysicsMotion | None = Field(None, description="The target-motion trial (test motion).")
    penetration: float = Field(..., ge=0, description="Deepest hand-object or hand-hand penetration at the "
                               "pregrasp, m.")
    tip_gaps: list[float] = Field(default_factory=list, description="Per fingertip, the signed distance from its "
                                  "real mesh to the object at the grasp pose, m (negative: penetrating).")
    touching_after_squeeze: int = Field(..., ge=0, description="Hand bodies touching the object after the squeeze "
                                        "(first push).")
    pregrasp: list[float] = Field(default_factory=list, description="Joint targets of the pregrasp (contacts 1 cm "
                                  "out), in `joint_names` order.")
    squeeze: list[float] = Field(default_factory=list, description="Joint targets of the squeeze (contacts 1 cm "
                                 "in, within the joint limits), in `joint_names` order.")
    seconds: float = Field(..., ge=0, description="Wall time of the test.")
    object_pieces: str = Field(..., description="How the object was built: hull (the sent mesh, convex), "
                               "mesh_patches (non-convex mesh), point_hull (points only, lying on their convex "
                               "hull) or point_patches (other points).")


class Quality(WireModel):
    """Verification figures of one proposal (docs/evaluation.md)."""

    success: bool = Field(..., description="All criteria below met (verification on the exact geometry).")
    converged: bool = Field(..., description="The refinement's own, stricter stopping test held (fingertips within "
                            "2 mm on the points' surface); a proposal can succeed without it.")
    reason: str = Field(..., description="Why refinement stopped: converged, verified (verification accepted a "
                        "nearly converged pose), stalled, max_iterations, deadline, ...")
    iterations: int = Field(..., ge=0, description="Refinement iterations spent on this proposal, restarts included.")
    wrench_residual: float = Field(..., ge=0, description="‖Σ G f − w‖² for the normalised target.")
    max_tip_distance: float = Field(..., ge=0, description="Largest |Φ(p_tip)| of a contact fingertip, m.")
    penetration_depth: float = Field(..., ge=0, description="Deepest hand–object penetration (exact), m.")
    self_collision_depth: float = Field(..., ge=0, description="Deepest hand self-penetration, m.")
    epsilon: float | None = Field(None, description="Ferrari–Canny ε (force closure), > 0 when closed.")
    failures: list[str] = Field(
        default_factory=list,
        description="The verification criteria the proposal misses (empty when it succeeds): wrench_residual, "
        "tip_distance, penetration, self_collision, not_force_closure, friction_cone.",
    )
    geometry: str | None = Field(
        None,
        description="The object surface verification measured on: 'mesh' (the sent mesh) or 'points' (the "
        "oriented points' surface, which keeps concavities).",
    )
    physics: PhysicsQuality | None = Field(
        None, description="The simulated grasp test (rigid objects with a robot, unless `options.simulate` is "
        "false); `success` then also requires that the object held (a failed test adds 'physics' to `failures`).",
    )


class IterationRecord(WireModel):
    """One SOCP iteration (returned with ``options.return_history``)."""

    residual: float
    tip_distance: float
    step: float


class HandMesh(WireModel):
    """The hand's collision meshes posed at a proposal (world frame, m), merged, for viewers."""

    vertices: Annotated[np.ndarray, spec("V", 3)]
    faces: Annotated[np.ndarray, spec("F", 3, kind="int")]


class Proposal(WireModel):
    """One solution: H contacts, their forces, and the hand configuration that makes them."""

    contact_points: Rows3
    contact_normals: Rows3
    forces: Rows3
    fingertips: list[str] = Field(
        default_factory=list, description="The fingertip link at each contact (empty without a robot)."
    )
    palm_position: Vec3 | None = Field(None, description="The palm's position, m (None without a robot).")
    palm_quaternion: Quaternion | None = Field(None, description="The palm's orientation (w, x, y, z).")
    joint_names: list[str] = Field(default_factory=list)
    joint_values: Vector = Field(
        default_factory=lambda: np.zeros(0), description="Joint values in ``joint_names`` order (rad or m)."
    )
    quality: Quality
    contact_source: str | None = Field(
        None,
        description="Where the contacts came from: network, given (the caller's contacts, each within 5 mm of "
        "its given point: see `contact_shift`), given_moved (the caller's contacts, at least one moved farther "
        "than 5 mm by the refinement), random, direct_grasp, opposed (a gripper asked to hold the object: its two "
        "pads on opposite faces, network-weighted), random_fallback "
        "(the network's heatmap had no point above the selection threshold, so random contacts were refined) "
        "or motion_fallback (a deformable's flat heatmap: the points the task moves most, with its motion).",
    )
    contact_shift: Vector | None = Field(
        None,
        description="Method 'contacts': how far (m) each contact lies from the caller's point of the same index "
        "(`contacts.points` order; never more contacts than given). Over 5 mm anywhere: `contact_source` is "
        "given_moved. Unset for the other methods.",
    )
    hand_spheres: Annotated[np.ndarray, spec("S", 4)] | None = Field(
        None, description="The hand's collision spheres at this pose: centre (world, m) and radius, for viewers."
    )
    hand_mesh: HandMesh | None = Field(
        None, description="The hand's collision meshes at this pose (what the contacts were verified on)."
    )
    history: list[IterationRecord] | None = None
    contact_motions: Rows3 | None = Field(
        None, description="Deformables: the post-contact motion of each contact (m): grasp it and move it so."
    )
    rollout_points: Rows3 | None = Field(
        None, description="Deformables with `options.simulate_rollout`: where the object's points end after the "
        "simulated manipulation (N, 3), m, in the request's order.",
    )
    shape_error: float | None = Field(
        None, ge=0, description="Deformables with `options.simulate_rollout`: mean distance between the rollout "
        "and the target over the most-moving points, in the paper's 2 m normalised cube.",
    )
    network_sample: int | None = Field(
        None, ge=0, description="Which of the network's latent samples proposed these contacts."
    )
    network_forces: Rows3 | None = Field(
        None, description="The network's force prediction at each of its contacts (its normalised units), beside the "
        "refined `forces`.",
    )

    @field_validator("palm_position", "palm_quaternion", mode="before")
    @classmethod
    def _empty_is_none(cls, value: object) -> object:
        """An empty palm pose is no pose (gRPC sends an unset repeated field as an empty one)."""
        return None if isinstance(value, list | tuple) and len(value) == 0 else value


class SynthesisResult(WireModel):
    """The answer to one request."""

    hand: str | None = Field(None, description="The hand's name (None for a request without a robot).")
    model_version: str
    proposals: list[Proposal]
    heatmap: PerPoint | None = Field(
        None, description="The network's contact heatmap (return_heatmap): the sample the best proposal came from."
    )
    force_map: Points | None = Field(None, description="The network's force map of the same sample (return_force_map).")
    heatmaps: Annotated[np.ndarray, spec("K", "N")] | None = Field(
        None, description="Every latent sample's heatmap (return_all_heatmaps), row k for `network_sample` k."
    )
    timings: dict[str, float] = Field(default_factory=dict, description="Seconds per stage.")

    @property
    def best(self) -> Proposal | None:
        """The first successful proposal, else the first one."""
        return next((p for p in self.proposals if p.quality.success), self.proposals[0] if self.proposals else None)
