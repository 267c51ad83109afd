"""Grasp sets: the linear programme that says whether a grasp can produce a task, and a shard's sets."""

from __future__ import annotations

import numpy as np

from manifoundation.core.refine.grasp import grasp_maps
from research.data.grasp_sets import feasible_forces, grasps_in_mask, shard_grasp_sets

CENTRE, LENGTH = np.zeros(3), 0.05


def _pinch(axis: int) -> tuple[np.ndarray, np.ndarray]:
    """Two contacts on opposite faces of a 10 cm cube, across ``axis``."""
    c = np.zeros((2, 3))
    c[0, axis], c[1, axis] = 0.05, -0.05
    return c, c / 0.05


def test_feasible_forces_make_the_wrench_within_cones_and_bounds() -> None:
    c, n = _pinch(0)
    lift = np.array([0.0, 0.0, 1.0, 0.0, 0.0, 0.0])
    f = feasible_forces(c, n, 0.8, np.eye(6), lift, CENTRE, LENGTH)
    assert f is not None
    np.testing.assert_allclose(np.einsum("mij,mj->i", grasp_maps(c, CENTRE, LENGTH), f), lift, atol=1e-7)
    normal = np.einsum("ij,ij->i", f, -n)
    assert np.all(normal <= 1 + 1e-9) and np.all(np.linalg.norm(f + normal[:, None] * n, axis=1) <= 0.8 * normal + 1e-9)
    # a lift of 1 needs a tangential 0.5 per contact: at normal force ≤ 1 and μ = 0.3 the cones give 0.3 at most
    assert feasible_forces(c, n, 0.3, np.eye(6), lift, CENTRE, LENGTH) is None
    push = np.array([3.0, 0.0, 0.0, 0.0, 0.0, 0.0])  # larger than two unit normal forces can give
    assert feasible_forces(c, n, 0.8, np.eye(6), push, CENTRE, LENGTH) is None


def _shard() -> dict[str, np.ndarray]:
    """One object, one hand, three examples: two by a pinch across x (a lift, a twist about y), one across y."""
    px, nx = _pinch(0)
    py, ny = _pinch(1)
    contacts = np.stack([px, px, py])
    normals = np.stack([nx, nx, ny])
    lift = np.array([[0.0, 0.0, 0.25], [0.0, 0.0, 0.25]])  # forces of the examples (tangential, inside μ)
    lift_n = lift - 0.5 * nx
    twist_y = np.array([[0.0, 0.0, -0.3], [0.0, 0.0, 0.3]]) - 0.5 * nx  # net force 0, torque about y
    squeeze = -0.5 * ny  # the zero wrench
    forces = np.stack([lift_n, twist_y, squeeze])
    return {
        "num_examples": np.asarray(3), "obj_index": np.zeros(3, dtype=np.int64), "hand": np.array(["g"] * 3),
        "contacts": contacts, "contact_normals": normals, "forces": forces, "num_contacts": np.full(3, 2),
        "friction": np.full(3, 0.8), "articulated": np.zeros(3, dtype=bool), "joint_type": np.array([""] * 3),
        "joint_axis": np.zeros((3, 3)), "joint_origin": np.zeros((3, 3)),
        "object_centre": CENTRE[None], "object_length": np.array([LENGTH]),
    }  # fmt: skip


def test_a_shard_example_keeps_its_own_grasp_first_and_the_others_that_can_do_its_task() -> None:
    sets = shard_grasp_sets(_shard())
    # the lift and the squeeze: either pinch can; the twist about y: a pinch across y has no lever arm about y
    assert sets.count.tolist() == [2, 1, 2]
    np.testing.assert_allclose(sets.contacts[0, 0, :2], _pinch(0)[0])
    np.testing.assert_allclose(sets.contacts[0, 1, :2], _pinch(1)[0])
    assert np.isnan(sets.contacts[1, 1]).all()

def _sphere_points(n: int = 200) -> np.ndarray:
    k = np.arange(n) + 0.5
    phi, theta = np.arccos(1 - 2 * k / n), np.pi * (1 + 5**0.5) * k
    return 0.05 * np.stack([np.cos(theta) * np.sin(phi), np.sin(theta) * np.sin(phi), np.cos(phi)], axis=1)


def test_a_grasp_is_in_the_mask_when_every_contact_is() -> None:
    points = _sphere_points()
    mask = points[:, 0] > 0  # the +x half
    sets = np.full((3, 2, 3), np.nan)
    sets[0] = [[0.05, 0, 0], [0.03, 0.04, 0]]
    sets[1] = [[0.05, 0, 0], [-0.05, 0, 0]]  # one contact outside
    sets[2, 0] = [0.0, 0.0, 0.05]  # one contact, padding after it; nearest point at x ≈ 0
    inside = grasps_in_mask(points, mask, sets, 2)
    assert inside.tolist() == [True, False, False]


def test_a_shard_keeps_as_many_valid_grasps_as_its_max_set_says() -> None:
    shard = _shard()
    shard["max_set"] = np.asarray(1)
    sets = shard_grasp_sets(shard)
    assert sets.contacts.shape[1] == 1
    assert sets.count.tolist() == [1, 1, 1]
    np.testing.assert_allclose(sets.contacts[2, 0, :2], _pinch(1)[0])
