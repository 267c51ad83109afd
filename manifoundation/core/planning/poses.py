"""Rigid poses of the object (and of the hand carried with it): position + unit quaternion (w, x, y, z).

A `Pose` places a body frame in the world: a point ``p`` of the body is at ``R p + t`` in the world. Composition
follows the matrices: ``(a @ b).matrix() == a.matrix() @ b.matrix()``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.spatial.transform import Rotation, Slerp


def quaternion_matrix(quaternion: np.ndarray) -> np.ndarray:
    """The (3, 3) rotation matrix of a unit quaternion (4,) (w, x, y, z) (plain numpy: the planner's validity
    test calls this thousands of times, and a scipy ``Rotation`` costs ~20 µs to build)."""
    w, x, y, z = (float(v) for v in quaternion)
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])


def _wxyz(rotation: Rotation) -> np.ndarray:
    q = np.asarray(rotation.as_quat(), dtype=np.float64)[[3, 0, 1, 2]]
    return q if q[0] >= 0 else -q  # one of the two equal quaternions, so that equal poses print equal


@dataclass(frozen=True)
class Pose:
    """A rigid pose: ``position`` (3,) m and ``quaternion`` (4,) unit, (w, x, y, z)."""

    position: np.ndarray = field(default_factory=lambda: np.zeros(3))
    quaternion: np.ndarray = field(default_factory=lambda: np.array([1.0, 0.0, 0.0, 0.0]))

    @classmethod
    def from_matrix(cls, matrix: np.ndarray) -> Pose:
        """The pose of a (4, 4) homogeneous transform."""
        m = np.asarray(matrix, dtype=np.float64)
        return cls(m[:3, 3].copy(), _wxyz(Rotation.from_matrix(m[:3, :3])))

    @classmethod
    def from_rotation(cls, position: np.ndarray, rotation: Rotation) -> Pose:
        """The pose of a position (3,) and a scipy ``Rotation``."""
        return cls(np.asarray(position, dtype=np.float64).copy(), _wxyz(rotation))

    @property
    def rotation(self) -> Rotation:
        """The orientation as a scipy ``Rotation``."""
        w, x, y, z = np.asarray(self.quaternion, dtype=np.float64)
        return Rotation.from_quat([x, y, z, w])

    def matrix(self) -> np.ndarray:
        """The (4, 4) homogeneous transform body → world."""
        m = np.eye(4)
        m[:3, :3] = quaternion_matrix(self.quaternion)
        m[:3, 3] = self.position
        return m

    def __matmul__(self, other: Pose) -> Pose:
        return Pose.from_rotation(
            self.rotation.apply(np.asarray(other.position, dtype=np.float64)) + self.position,
            self.rotation * other.rotation,
        )

    def inverse(self) -> Pose:
        """The pose world → body."""
        inv = self.rotation.inv()
        return Pose.from_rotation(-inv.apply(np.asarray(self.position, dtype=np.float64)), inv)

    def apply(self, points: np.ndarray) -> np.ndarray:
        """Body points (N, 3) in the world (N, 3)."""
        return self.rotate(points) + np.asarray(self.position, dtype=np.float64)

    def rotate(self, vectors: np.ndarray) -> np.ndarray:
        """Body directions (N, 3) (normals) in the world (N, 3)."""
        world: np.ndarray = np.asarray(vectors, dtype=np.float64).reshape(-1, 3) @ quaternion_matrix(self.quaternion).T
        return world

    def translation_to(self, other: Pose) -> float:
        """Distance (m) between the two positions."""
        return float(np.linalg.norm(np.asarray(other.position) - np.asarray(self.position)))

    def angle_to(self, other: Pose) -> float:
        """Angle (rad, in [0, π]) of the rotation from this orientation to ``other``'s."""
        return float((other.rotation * self.rotation.inv()).magnitude())

    def interpolate(self, other: Pose, fraction: float) -> Pose:
        """The pose ``fraction`` ∈ [0, 1] of the way to ``other``: straight line and shortest-arc slerp (the
        interpolation OMPL's SE(3) space checks motions along)."""
        t = float(fraction)
        pos = (1 - t) * np.asarray(self.position) + t * np.asarray(other.position)
        rots = Rotation.concatenate([self.rotation, other.rotation])
        return Pose.from_rotation(pos, Slerp([0.0, 1.0], rots)([t])[0])

    def carry(self, start: Pose, end: Pose) -> Pose:
        """This pose (e.g. a palm) moved rigidly with a body that goes from ``start`` to ``end``."""
        return end @ start.inverse() @ self


IDENTITY = Pose()
