"""Core inputs and outputs of the synthesis pipeline (pure dataclasses; the worker maps the wire schemas here).


Mirrors ``manifoundation/contract`` (requests, tasks, results) field for field without importing it.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Literal

import numpy as np

from manifoundation.core.errors import Cancelled, InvalidInput, ModelUnavailable
from manifoundation.core.refine.state import HandPose

if TYPE_CHECKING:
    from manifoundation.core.physics import PhysicsResult
    from manifoundation.core.robots.hand import Hand

METHODS = ("network", "contacts", "direct_grasp", "random_contacts")
MAX_PROPOSALS = 16  # the contract's MAX_PROPOSALS (tests/test_contract_mirrors.py holds the copies equal)
TASK_KINDS = ("delta_pose", "point_motion", "target_points", "wrench", "force_closure", "joint_motion")
MATERIALS = ("rigid", "articulated", "cloth", "rope", "plasticine")


__all__ = [
    "MATERIALS",
    "METHODS",
    "TASK_KINDS",
    "Cancelled",
    "InvalidInput",
    "IterationOutput",
    "JointInput",
    "ModelUnavailable",
    "ProposalOutput",
    "QualityOutput",
    "SynthesisInput",
    "SynthesisOutput",
    "TaskInput",
]


@dataclass
class TaskInput:
    """What the manipulation should achieve (``kind`` picks the fields used).

    Attributes:
        kind: one of `TASK_KINDS`.
        translation: (3,) m, and rotation: (4,) wxyz about the centre of mass (``delta_pose``).
        motion: (N, 3) per-point displacement (``point_motion``).
        targets: (N, 3) target cloud, point-to-point (``target_points``).
        wrench: (6,) force N and torque N·m about the centre of mass (``wrench``).
        delta: signed joint displacement, rad or m (``joint_motion``).
        correspondence: ``target_points`` only: "index" or "unknown" (targets (M, 3) in any order).
    """

    kind: str
    translation: np.ndarray | None = None
    rotation: np.ndarray | None = None
    motion: np.ndarray | None = None
    targets: np.ndarray | None = None
    wrench: np.ndarray | None = None
    delta: float | None = None
    correspondence: str = "index"  # target_points: "index" (point i → target i) or "unknown" (registered)


@dataclass
class JointInput:
    """Articulation: ``type`` revolute|prismatic, unit ``axis`` (3,) through ``origin`` (3,), moving ``part_mask``
    (N,) bool."""

    type: str
    axis: np.ndarray
    origin: np.ndarray
    part_mask: np.ndarray


PhysicsMode = Literal["off", "check", "search"]
"""How a rigid request with a robot uses the simulated grasp test (`manifoundation.core.pipeline.physics_search`):
"off" — geometric verification only; "check" — each returned proposal is tested, counts as a success only when it
held, and the ones that held come first; "search" — every candidate is tested as it is made and more are drawn
until ``num_proposals`` held."""


def physics_mode(simulate: bool | None) -> PhysicsMode:
    """A request's ``options.simulate`` as a `PhysicsMode`: unset -> "check", true -> "search", false -> "off"."""
    return "check" if simulate is None else "search" if simulate else "off"


@dataclass
class SynthesisInput:
    """One synthesis request in core form.

    Attributes:
        points: (N, 3) object points (m). normals: (N, 3) outward unit normals, or None (estimated).
        hand: a `manifoundation.core.robots.Hand`.
        task: the task.
        material: one of `MATERIALS`. properties: friction, density, stretch, bending, youngs_modulus,
            poisson_ratio (those given).
        mask: (N,) bool, True where contact is allowed, or None.
        joint: articulation, or None.
        mesh_vertices, mesh_faces: optional watertight mesh (exact verification).
        contacts: (H, 3) given contacts (method "contacts").
        method: one of `METHODS`. num_proposals: K. refine: run the SOCP refinement.
        max_iterations: refinement cap. seed: seeds sampling. deadline: `time.monotonic()` value or None.
        return_history: keep per-iteration records. hand_key: cache key of the hand for the network.
        initial_pose: a caller's start for the refinement (e.g. a planner's grasp carried from its previous step):
            with it the pipeline refines this one pose (one proposal, source "initial_pose"), finds no contacts
            of its own and never restarts from other approaches.
        stop_after_verified: stop once this many proposals are verified: the later ones are neither refined
            nor returned (None: all ``num_proposals``).
        rollout_corrections: deformables with ``simulate_rollout``: rollouts a proposal that misses its target
            may spend correcting its motions (`manifoundation.core.pipeline.deformable_rollout`; 0: none).
        close_gaps: after a verified refinement, close the fingertips onto the object
            (`manifoundation.core.refine.close`; the closed pose is kept only where verification still accepts it;
            not for an ``initial_pose``, which stays as carried).
    """

    points: np.ndarray
    hand: Hand
    task: TaskInput
    normals: np.ndarray | None = None
    material: str = "rigid"
    properties: dict[str, float] = field(default_factory=dict)
    mask: np.ndarray | None = None
    joint: JointInput | None = None
    mesh_vertices: np.ndarray | None = None
    mesh_faces: np.ndarray | None = None
    contacts: np.ndarray | None = None
    method: str = "network"
    num_proposals: int = 1
    refine: bool = True
    max_iterations: int = 100
    seed: int = 0
    deadline: float | None = None
    return_history: bool = False
    simulate_rollout: bool = False  # deformables: simulate each answer and judge it by the shape metric
    handless: bool = False  # deformables without a robot: ``hand`` is only the network's manipulator input
    num_contacts: int | None = None  # contacts per proposal when handless (default 2)
    hand_key: str | None = None
    initial_pose: HandPose | None = None
    stop_after_verified: int | None = None
    rollout_corrections: int = 0
    close_gaps: bool = True
    simulate: PhysicsMode = "off"  # rigid, with a robot: the simulated grasp test (`PhysicsMode`)

    @property
    def candidates(self) -> int:
        """Starts drawn (network samples or contact sets): ``num_proposals``, or when searching (``simulate``
        "search") at least `SIMULATE_CANDIDATES`."""
        return max(self.num_proposals, SIMULATE_CANDIDATES) if self.simulate == "search" else self.num_proposals


@dataclass
class QualityOutput:
    """Verification figures of one proposal (see `manifoundation.core.refine.verify`).

    ``success`` is verification's verdict on the exact geometry; ``converged`` and ``reason`` are the refinement's
    own, stricter test (fingertips within 2 mm on the points' surface): a nearly converged or stalled attempt
    whose pose verification accepts is returned as it is (success, not converged, reason "verified" or
    "stalled") instead of being refined on or restarted.
    """

    success: bool
    converged: bool
    reason: str
    iterations: int
    wrench_residual: float  # ‖Σ G f − w‖² for the normalised target
    max_tip_distance: float
    penetration_depth: float
    self_collision_depth: float
    epsilon: float | None
    failures: list[str] = field(default_factory=list)
    geometry: str = "points"  # the object surface verification measured on: "mesh" or "points"


@dataclass
class IterationOutput:
    """One refinement iteration: residual ‖r*‖, max tip distance (m), trust-region scale."""

    residual: float
    tip_distance: float
    step: float


SIMULATE_CANDIDATES = 16
"""Searching (``simulate`` "search"): the fewest starts drawn, one after another until ``num_proposals`` held
(`physics_search`). On 43 third-party objects (K = 1, 0.3 μ design) the first answer held for LEAP in 24 with 8,
29 with 16; Allegro 33 and 35; the median request 4.3 → 4.6 s and 1.6 → 1.7 s, the 90th percentile 6.5 → 11.7 s and
4.0 → 6.6 s (those that find none search longer; research/results/physics.md)."""


@dataclass
class ProposalOutput:
    """One hand proposal: contacts (one per fingertip), forces, pose and quality."""

    contact_points: np.ndarray
    contact_normals: np.ndarray
    forces: np.ndarray
    fingertips: list[str]  # empty without a robot (deformables)
    palm_position: np.ndarray | None  # None without a robot
    palm_quaternion: np.ndarray | None
    joint_names: list[str]
    joint_values: np.ndarray | None
    quality: QualityOutput
    contact_source: str = "given"  # given|given_moved|random|network|random_fallback|motion_fallback|direct_grasp|...
    history: list[IterationOutput] | None = None
    contact_shift: np.ndarray | None = None  # (H,) method "contacts": each contact's distance from its given point, m
    contact_motions: np.ndarray | None = None  # (H, 3) post-contact motion per contact (deformables), m
    network_forces: np.ndarray | None = None  # (H, 3) the network's force prediction at its contacts (model units)
    network_sample: int | None = None  # which of the network's K latent samples the contacts came from
    rollout_points: np.ndarray | None = None  # (N, 3) deformables: the points after the simulated manipulation
    shape_error: float | None = None  # deformables: rollout vs target, most-moving points, normalised 2 m cube
    physics: PhysicsResult | None = None  # ``simulate``: the simulated grasp test's result
    squeeze_imbalance: float | None = None  # force closure: `manifoundation.core.refine.squeeze` (0 balanced … 2)

    def pose(self) -> HandPose:
        """The hand's pose at this proposal.

        Raises:
            ValueError: a proposal without a robot (a deformable's contacts for any gripper) has none.
        """
        if self.palm_position is None or self.palm_quaternion is None or self.joint_values is None:
            raise ValueError("this proposal has no hand pose (the request had no robot)")
        return HandPose(self.palm_position, self.palm_quaternion, self.joint_values)


@dataclass
class SynthesisOutput:
    """Proposals (successful ones first), optional network maps, and seconds per stage."""

    hand: str | None  # None for a deformable's contacts without a robot
    proposals: list[ProposalOutput]
    heatmap: np.ndarray | None = None
    heatmaps: np.ndarray | None = None  # (K, N) every latent sample's heatmap
    force_map: np.ndarray | None = None
    timings: dict[str, float] = field(default_factory=dict)

    @property
    def best(self) -> ProposalOutput | None:
        return next((p for p in self.proposals if p.quality.success), self.proposals[0] if self.proposals else None)
