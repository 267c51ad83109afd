"""The audit's data: the proposal it reads (:class:`AuditedGrasp`) and what it reports (:class:`AuditReport`)."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from research.audit.penetration import PenetrationAudit


@dataclass
class AuditedGrasp:
    """One grasp as the service reports it (plain numpy).

    Attributes:
        contact_points: (m, 3) world contact points (m).
        forces: (m, 3) forces the fingertips apply ON the object (N).
        fingertips: (m,) link name per contact.
        palm_position: (3,) world position of the palm frame.
        palm_quaternion: (4,) its orientation ``(w, x, y, z)``.
        joint_names: (n,) reported (free) joints.
        joint_values: (n,) their values.
    """

    contact_points: np.ndarray
    forces: np.ndarray
    fingertips: list[str]
    palm_position: np.ndarray
    palm_quaternion: np.ndarray
    joint_names: list[str]
    joint_values: np.ndarray

    def __post_init__(self) -> None:
        self.contact_points = np.asarray(self.contact_points, dtype=np.float64).reshape(-1, 3)
        self.forces = np.asarray(self.forces, dtype=np.float64).reshape(-1, 3)
        self.fingertips = [str(f) for f in self.fingertips]
        self.palm_position = np.asarray(self.palm_position, dtype=np.float64)
        self.palm_quaternion = np.asarray(self.palm_quaternion, dtype=np.float64)
        self.joint_names = [str(n) for n in self.joint_names]
        self.joint_values = np.asarray(self.joint_values, dtype=np.float64)

    @classmethod
    def from_mapping(cls, proposal: Mapping[str, Any]) -> AuditedGrasp:
        """From a mapping with the fields above (e.g. a decoded proposal; extra keys are ignored)."""
        keys = ("contact_points", "forces", "fingertips", "palm_position", "palm_quaternion", "joint_names")
        return cls(**{k: proposal[k] for k in (*keys, "joint_values")})


@dataclass
class ContactAudit:
    """Measurements at one contact.

    Attributes:
        link: its fingertip link.
        finger_distance: distance from the point to the posed link surface (m; inf if the link is unknown).
        object_distance: distance from the point to the object surface (m).
        normal: (3,) outward object normal used.
        normal_force: ``f·(−n)`` (N; negative: pulling).
        tangential_force: ``‖f_t‖`` (N).
        friction_ratio: tangential / normal (inf when not pushing; 0 for a zero force).
    """

    link: str
    finger_distance: float
    object_distance: float
    normal: np.ndarray
    normal_force: float
    tangential_force: float
    friction_ratio: float


@dataclass
class AuditReport:
    """The audit's verdict and its measurements.

    Attributes:
        passed: no criterion failed.
        failures: one message per failed check.
        notes: caveats (approximations used, checks not possible).
        contacts: per-contact measurements.
        penetration: the penetration found (``None`` without an object mesh or a pose).
        joint_values: every moving joint's value used for the pose (reported and derived).
        limit_violations: joint → excess over its limits.
        wrench: (6,) achieved total scaled wrench ``[F, τ / L]``.
        target_cosine: cosine with the scaled target (``None`` without a target).
        closure_epsilon: ε of the linearised cones (``None`` unless closure was asked).
        centre: (3,) the wrench reference point.
        length: the torque scale L (m).
    """

    passed: bool
    failures: list[str]
    notes: list[str] = field(default_factory=list)
    contacts: list[ContactAudit] = field(default_factory=list)
    penetration: PenetrationAudit | None = None
    joint_values: dict[str, float] = field(default_factory=dict)
    limit_violations: dict[str, float] = field(default_factory=dict)
    wrench: np.ndarray | None = None
    target_cosine: float | None = None
    closure_epsilon: float | None = None
    centre: np.ndarray | None = None
    length: float | None = None

    @property
    def finger_distances(self) -> np.ndarray:
        """(m,) contact → fingertip surface distances."""
        return np.array([c.finger_distance for c in self.contacts])

    @property
    def object_distances(self) -> np.ndarray:
        """(m,) contact → object surface distances."""
        return np.array([c.object_distance for c in self.contacts])

    @property
    def friction_ratios(self) -> np.ndarray:
        """(m,) tangential / normal force."""
        return np.array([c.friction_ratio for c in self.contacts])

    @property
    def normal_forces(self) -> np.ndarray:
        """(m,) pushing force components (N)."""
        return np.array([c.normal_force for c in self.contacts])
