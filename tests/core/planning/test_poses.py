import numpy as np
from scipy.spatial.transform import Rotation

from manifoundation.core.planning import Pose


def _random_pose(rng):
    return Pose.from_rotation(rng.normal(size=3), Rotation.random(random_state=int(rng.integers(1 << 30))))


def test_composition_and_inverse_follow_the_matrices():
    rng = np.random.default_rng(0)
    a, b = _random_pose(rng), _random_pose(rng)
    np.testing.assert_allclose((a @ b).matrix(), a.matrix() @ b.matrix(), atol=1e-12)
    np.testing.assert_allclose((a @ a.inverse()).matrix(), np.eye(4), atol=1e-12)
    pts = rng.normal(size=(5, 3))
    np.testing.assert_allclose(a.apply(pts), pts @ a.matrix()[:3, :3].T + a.position, atol=1e-12)


def test_interpolation_ends_and_midpoint_angle():
    a = Pose(np.zeros(3))
    b = Pose.from_rotation(np.array([1.0, 0, 0]), Rotation.from_rotvec([0, 0, np.pi / 2]))
    np.testing.assert_allclose(a.interpolate(b, 0.0).matrix(), a.matrix(), atol=1e-12)
    np.testing.assert_allclose(a.interpolate(b, 1.0).matrix(), b.matrix(), atol=1e-12)
    mid = a.interpolate(b, 0.5)
    np.testing.assert_allclose(mid.position, [0.5, 0, 0])
    assert abs(a.angle_to(mid) - np.pi / 4) < 1e-12


def test_carry_keeps_the_relative_pose():
    rng = np.random.default_rng(1)
    start, end, hand = _random_pose(rng), _random_pose(rng), _random_pose(rng)
    moved = hand.carry(start, end)
    np.testing.assert_allclose((start.inverse() @ hand).matrix(), (end.inverse() @ moved).matrix(), atol=1e-12)
