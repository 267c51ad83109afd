"""A synthesis request: object + task + robot + options (+ optional given contacts)."""

from __future__ import annotations

from enum import StrEnum

from pydantic import Field, model_validator

from manifoundation.contract.common import Rows3, WireModel
from manifoundation.contract.objects import Material, ObjectIn
from manifoundation.contract.robots import RobotIn
from manifoundation.contract.tasks import JointMotionTask, PointMotionTask, TargetPointsTask, TaskIn

MAX_TIMEOUT_S = 600.0
DEFAULT_TIMEOUT_S = 30.0
"""How long a caller waits for a synchronous answer unless it says (``options.timeout``; gRPC's unset field too)."""
MAX_PROPOSALS = 16
"""Most hand proposals one request (or one plan's new grasp) may ask for: ``num_proposals``, ``stop_after_verified``."""


class Method(StrEnum):
    """How contacts are found before refinement."""

    AUTO = "auto"  # given contacts when present, else the network
    NETWORK = "network"  # the CVAE's heatmap + NMS (paper §III-A)
    CONTACTS = "contacts"  # the request's own contacts
    DIRECT_GRASP = "direct_grasp"  # baseline: open hand, approach the centre, close on contact
    RANDOM_CONTACTS = "random_contacts"  # baseline: random surface points in the allowed region


class SynthesisOptions(WireModel):
    """How to run the synthesis."""

    method: Method = Method.AUTO
    num_proposals: int = Field(
        1, ge=1, le=MAX_PROPOSALS, description="Hand proposals to return (K latent samples)."
    )
    stop_after_verified: int | None = Field(
        None, ge=1, le=MAX_PROPOSALS, description="Stop once this many proposals are verified: the later ones are "
        "neither refined nor returned, so fewer than `num_proposals` may come back (a caller that needs one grasp, "
        "with fallbacks, waits only for the first good one). Unset: all `num_proposals`.",
    )
    refine: bool = Field(True, description="Run the SOCP pose refinement (off: initial pose only).")
    max_iterations: int = Field(100, ge=1, le=500)
    seed: int = Field(0, ge=0, le=2**31 - 1, description="Seeds sampling; same seed, same answer.")
    timeout: float = Field(DEFAULT_TIMEOUT_S, gt=0, le=MAX_TIMEOUT_S, description="Seconds the caller will wait.")
    return_heatmap: bool = False
    return_force_map: bool = False
    return_history: bool = False
    return_all_heatmaps: bool = Field(
        False, description="Return every latent sample's heatmap (`heatmaps`, K × N; each proposal names its "
        "`network_sample`), not only the best proposal's.",
    )
    return_hand_mesh: bool = Field(
        False,
        description="Return each proposal's posed hand collision meshes (`hand_mesh`, for viewers; about "
        "100-400 kB a proposal).",
    )
    num_contacts: int | None = Field(
        None, ge=1, le=8, description="Deformables without a robot: contacts per proposal (default 2). With a "
        "robot the contacts are its fingertips.",
    )
    simulate_rollout: bool = Field(
        False,
        description="Deformables: apply each proposal's contacts and motions in the simulator (MuJoCo, on a body "
        "rebuilt from the points, resting on a table under its lowest point) and judge success by the paper's "
        "shape metric against the target; returns `rollout_points`. About 0.5-2 s a proposal.",
    )
    simulate: bool | None = Field(
        None,
        description="Rigid objects with a robot: the simulated grasp test (MuJoCo, DexGraspBench's protocol: "
        "pregrasp → grasp → squeeze, then 1 N pushes along ±x, ±y, ±z for 2 s; for a `delta_pose` task instead "
        "gravity on and the palm carried along the task's motion over 1 s, success within 1 cm and 10° of the "
        "target pose; docs/physics.md). Unset (the default): each returned proposal is tested once, "
        "`quality.success` requires that it passed and the ones that passed come first (about 0.05-0.35 s a "
        "proposal on one core). true: search — up to 16 candidates (or `num_proposals`) are refined and tested one "
        "after another until `num_proposals` passed, the best first (held and verified, held, verified); a "
        "median of 0.8-4.6 s a request by hand instead of 0.5-0.9 s. false: no test (geometric verification "
        "only: faster, and a proposal it calls a success may not hold). `quality.physics` carries the test "
        "(`test`: closure or motion).",
    )
    rollout_corrections: int = Field(
        0, ge=0, le=8, description="Deformables with `simulate_rollout`: a proposal whose rollout misses the "
        "target may spend up to this many more rollouts correcting its post-contact motions (closed loop through "
        "the simulator: a plasticine press springs back, so pushing by the target's displacement stops short); "
        "the best rollout's motions are returned and `quality.iterations` counts the rollouts spent.",
    )

    @model_validator(mode="after")
    def _enough_within_proposals(self) -> SynthesisOptions:
        if self.stop_after_verified is not None and self.stop_after_verified > self.num_proposals:
            raise ValueError(f"stop_after_verified: {self.stop_after_verified} is more than num_proposals "
                             f"({self.num_proposals}): it could never stop early")
        if self.rollout_corrections and not self.simulate_rollout:
            raise ValueError(f"rollout_corrections: {self.rollout_corrections} needs simulate_rollout: the "
                             "corrections are rollouts")
        return self


class ContactsIn(WireModel):
    """Contacts chosen by the caller (method "contacts"): H points on the object. The forces are the refinement's
    to find (the ones that produce the task's wrench), so the caller gives none."""

    points: Rows3

    @model_validator(mode="after")
    def _sizes(self) -> ContactsIn:
        if not 1 <= len(self.points) <= 8:
            raise ValueError(f"contacts.points: {len(self.points)} contacts, need 1..8")
        return self


class SynthesisRequest(WireModel):
    """Body of ``POST /v1/synthesize`` and ``POST /v1/jobs``."""

    object: ObjectIn
    task: TaskIn
    robot: RobotIn | None = Field(
        None, description="The hand. Optional only for a deformable object with a per-point task (point_motion, "
        "target_points): the answer is then contact points with their post-contact motions, for any gripper.",
    )
    options: SynthesisOptions = Field(default_factory=SynthesisOptions)
    contacts: ContactsIn | None = None

    @model_validator(mode="after")
    def _consistent(self) -> SynthesisRequest:
        n = self.object.num_points
        if isinstance(self.task, PointMotionTask) and self.task.motion.shape != (n, 3):
            raise ValueError(f"task.motion: shape {self.task.motion.shape} does not match points ({n}, 3)")
        if (isinstance(self.task, TargetPointsTask) and self.task.correspondence == "index"
                and self.task.targets.shape != (n, 3)):  # fmt: skip
            raise ValueError(f"task.targets: shape {self.task.targets.shape} does not match points ({n}, 3)")
        if isinstance(self.task, JointMotionTask) and self.object.material is not Material.ARTICULATED:
            raise ValueError("task: joint_motion needs an articulated object")
        if self.options.method is Method.CONTACTS and self.contacts is None:
            raise ValueError("contacts: required with options.method 'contacts'")
        if self.robot is None and not self.handless:
            raise ValueError("robot: required, except for a deformable object (cloth, rope, plasticine) with a "
                             "point_motion or target_points task")  # fmt: skip
        if self.robot is not None and self.options.num_contacts is not None:
            raise ValueError("options.num_contacts: only without a robot (with one, the contacts are its fingertips)")
        return self

    @property
    def handless(self) -> bool:
        """A deformable's per-point task, which a request may send without a robot."""
        deformable = self.object.material in (Material.CLOTH, Material.ROPE, Material.PLASTICINE)
        return deformable and isinstance(self.task, PointMotionTask | TargetPointsTask)
