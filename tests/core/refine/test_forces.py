import numpy as np
import pytest

from manifoundation.core.refine.closure import ferrari_canny
from manifoundation.core.refine.forces import solve_forces, solve_forces_cvxpy
from manifoundation.core.refine.wrench import articulated_task, closure_task, rigid_task


def _sphere_contacts(angles_deg, radius=0.05):
    a = np.deg2rad(angles_deg)
    pts = radius * np.stack([np.cos(a), np.sin(a), np.zeros_like(a)], axis=1)
    return pts, pts / radius


def test_native_matches_cvxpy_reference_on_random_instances():
    rng = np.random.default_rng(1)
    for i in range(6):  # closure twice, rigid wrenches four times (each CVXPY build costs ≈ 0.8 s)
        m = int(rng.integers(2, 5))
        normals = rng.normal(size=(m, 3))
        normals /= np.linalg.norm(normals, axis=1, keepdims=True)
        points = normals * 0.05 + rng.normal(scale=0.005, size=(m, 3))
        task = closure_task(np.zeros(3), 0.05) if i % 3 == 0 else rigid_task(rng.normal(size=6), np.zeros(3), 0.05)
        a = solve_forces(task, points, normals, 0.5)
        b = solve_forces_cvxpy(task, points, normals, 0.5)
        assert np.isfinite(a.residual_norm)
        assert a.residual_norm == pytest.approx(b.residual_norm, abs=1e-5)


def test_antipodal_box_grasp_is_closure_with_pads():
    points = np.array([[0.04, 0, 0], [-0.04, 0, 0]])
    normals = np.array([[1.0, 0, 0], [-1.0, 0, 0]])
    sol = solve_forces(closure_task(np.zeros(3), 0.05), points, normals, 0.5)
    assert sol.residual_norm < 1e-6
    np.testing.assert_allclose(sol.forces[:, 0], [-0.5, 0.5], atol=1e-5)  # squeezing, Σ f_n = 1
    assert ferrari_canny(points, normals, 0.5, np.zeros(3), 0.05) == 0.0  # point contacts: not closure
    assert ferrari_canny(points, normals, 0.5, np.zeros(3), 0.05, torsional=0.005) > 0  # soft pads


def test_three_fingertips_on_a_sphere():
    points, normals = _sphere_contacts([0, 120, 240])
    sol = solve_forces(closure_task(np.zeros(3), 0.05), points, normals, 0.5)
    assert sol.residual_norm < 1e-6
    assert np.all(-np.einsum("ij,ij->i", sol.forces, normals) > 0)
    assert ferrari_canny(points, normals, 0.5, np.zeros(3), 0.05) > 0
    # all three on one side cannot hold it
    points, normals = _sphere_contacts([0, 20, 40])
    assert solve_forces(closure_task(np.zeros(3), 0.05), points, normals, 0.5).residual_norm > 1e-3
    assert ferrari_canny(points, normals, 0.5, np.zeros(3), 0.05) == 0.0


def test_wrench_outside_the_cone_leaves_a_residual_not_an_error():
    points, normals = _sphere_contacts([0, 10])
    # both contacts on +x can only push towards −x; ask for +x
    sol = solve_forces(rigid_task(np.array([1.0, 0, 0, 0, 0, 0]), np.zeros(3), 0.05), points, normals, 0.5)
    assert sol.status in ("Solved", "AlmostSolved")
    assert sol.residual_norm > 0.5


def test_revolute_door_only_one_face_can_open_it():
    # door: plate x in [0, 0.4], hinge along +z through the origin; open = positive torque about +z
    task = articulated_task("revolute", [0, 0, 1], [0, 0, 0], centre=np.array([0.2, 0, 0]), length=0.2)
    back = solve_forces(task, np.array([[0.3, -0.01, 0]]), np.array([[0, -1.0, 0]]), 0.5)
    front = solve_forces(task, np.array([[0.3, 0.01, 0]]), np.array([[0, 1.0, 0]]), 0.5)
    assert back.residual_norm < 1e-6 and back.forces[0, 1] > 0  # pushes the back face along +y
    assert front.residual_norm == pytest.approx(1.0, abs=1e-4)  # the front face can only close it


def test_forces_are_projected_into_their_cones():
    from manifoundation.core.refine.forces import project_to_cones

    normals = np.array([[0.0, 0.0, 1.0], [0.0, 0.0, 1.0], [0.0, 0.0, 1.0]])
    forces = np.array([[0.3, 0.0, -1.0], [1.0, 0.0, -1.0], [0.1, 0.0, 1.0]])  # inside, outside, pulling
    out = project_to_cones(forces, normals, 0.5)
    assert np.allclose(out[0], forces[0])
    push = -out[1, 2]
    assert np.hypot(out[1, 0], out[1, 1]) == pytest.approx(0.5 * push)
    rng = np.random.default_rng(0)  # the projection is the cone's nearest point to the force
    for _ in range(200):
        fn = rng.uniform(0, 2)
        t = rng.normal(size=2)
        t *= 0.5 * fn / np.linalg.norm(t) * rng.uniform(0, 1)
        other = np.array([t[0], t[1], -fn])
        assert np.linalg.norm(out[1] - forces[1]) <= np.linalg.norm(other - forces[1]) + 1e-12
    assert np.allclose(out[2], 0.0)


def test_closure_is_designed_for_a_narrower_cone_with_three_or_more_contacts():
    """A thumb on a face and two fingers on the opposite one, their normals tilted 20° (tan 20° = 0.364): the
    fingers' pushes balance only with that much friction. Three or more contacts are designed for 0.3 μ
    (`CLOSURE_CONE_SHRINK`): 0.30 at μ 1 is too little, 0.45 at μ 1.5 enough. Two contacts keep 0.9 μ: 0.45 at μ 0.5
    holds the thumb and one tilted finger on the line between them, 0.27 at μ 0.3 does not."""
    tilt = np.deg2rad(20.0)
    finger = np.array([np.cos(tilt), 0.0, np.sin(tilt)])
    points = np.array([[-0.03, 0.0, 0.0], [0.03, 0.02, 0.0], [0.03, -0.02, 0.0]])
    normals = np.array([[-1.0, 0.0, 0.0], finger, finger])
    task = closure_task(np.zeros(3), 0.05)
    assert solve_forces(task, points, normals, 1.0).residual_norm > 1e-3
    assert solve_forces(task, points, normals, 1.5).residual_norm < 1e-6
    two = np.array([[-0.03, 0.0, 0.0], [0.03, 0.0, 0.0]])
    assert solve_forces(task, two, normals[:2], 0.5).residual_norm < 1e-6
    assert solve_forces(task, two, normals[:2], 0.3).residual_norm > 1e-3
