import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from manifoundation.core.refine.wrench import (
    articulated_task,
    characteristic_length,
    closure_task,
    joint_projection,
    kabsch,
    motion_from_pose,
    normalise,
    rigid_task,
    wrench_from_motion,
)


def test_wrench_from_motion_is_inverse_dynamics():
    inertia = np.diag([0.1, 0.2, 0.4])
    w = wrench_from_motion(np.array([0.1, 0, 0]), np.array([0, 0, 0.5]), mass=2.0, inertia=inertia, dt=0.5)
    np.testing.assert_allclose(w, 2 / 0.25 * np.array([0.2, 0, 0, 0, 0, 0.2]))


def test_normalise_rejects_zero():
    with pytest.raises(ValueError, match="force closure"):
        normalise(np.zeros(6))


def test_rigid_task_scales_torque_and_is_unit():
    task = rigid_task(np.array([0, 0, 0, 0, 0, 0.1]), np.zeros(3), length=0.1)
    np.testing.assert_allclose(task.target, [0, 0, 0, 0, 0, 1.0])
    assert task.rows == 6 and not task.closure
    assert closure_task(np.zeros(3), 0.1).closure


def test_motion_from_pose_and_kabsch_round_trip():
    rng = np.random.default_rng(0)
    pts = rng.normal(size=(50, 3))
    rot = Rotation.from_rotvec([0.1, -0.2, 0.3]).as_matrix()
    r, t = kabsch(pts, pts @ rot.T + [0.1, 0, 0])
    np.testing.assert_allclose(r, rot, atol=1e-9)
    dx, dth = motion_from_pose(r, t, np.zeros(3))
    np.testing.assert_allclose(dx, [0.1, 0, 0], atol=1e-9)
    np.testing.assert_allclose(dth, [0.1, -0.2, 0.3], atol=1e-9)


def test_joint_projections():
    a, o = np.array([0, 0, 1.0]), np.array([1.0, 0, 0])
    np.testing.assert_allclose(joint_projection("revolute", a, o), [[0, -1, 0, 0, 0, 1]])
    np.testing.assert_allclose(joint_projection("prismatic", a, o), [[0, 0, 1, 0, 0, 0]])
    # a force (0, 1, 0) at x = 2 about an axis through x = 1: torque +1 about z
    w = np.array([0, 1.0, 0, *np.cross([2.0, 0, 0], [0, 1.0, 0])])
    assert joint_projection("revolute", a, o)[0] @ w == pytest.approx(1.0)
    with pytest.raises(ValueError):
        joint_projection("spherical", a, o)


def test_articulated_task_row_matches_projection():
    centre, length = np.array([0.2, 0, 0]), 0.2
    task = articulated_task("revolute", [0, 0, 1], [0, 0, 0], centre, length)
    # scaled wrench of a force (0, 1, 0) at p = (0.4, 0, 0): [f; (p - c) × f / ρ]
    f, p = np.array([0, 1.0, 0]), np.array([0.4, 0, 0])
    scaled = np.concatenate([f, np.cross(p - centre, f) / length])
    assert (task.projection @ scaled)[0] == pytest.approx(0.4 / length)


def test_characteristic_length():
    assert characteristic_length(np.array([[0.3, 0, 0], [0, 0.1, 0]]), np.zeros(3)) == pytest.approx(0.3)
