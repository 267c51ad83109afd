"""Fixtures shared by the science tests (tests/core, tests/research; their conftest imports them): a box, the Panda
gripper, a LEAP hand
initialised on a cube."""

import numpy as np
import pytest
import trimesh


@pytest.fixture(scope="session")
def box():
    """A 4 x 6 x 6 cm box: mesh, 1024 surface points, normals."""
    mesh = trimesh.creation.box(extents=[0.04, 0.06, 0.06])
    pts, faces = trimesh.sample.sample_surface(mesh, 1024, seed=0)
    return mesh, np.asarray(pts), np.asarray(mesh.face_normals[faces])


@pytest.fixture(scope="session")
def gripper():
    from manifoundation.core.robots import get_hand

    return get_hand("panda_gripper")


@pytest.fixture(scope="session")
def leap_on_a_box():
    """A LEAP hand initialised on a 6 cm cube's points, and a lift: (hand, mesh, field, task, start pose)."""
    from manifoundation.core.refine.field import PointCloudField
    from manifoundation.core.refine.initialise import initialise
    from manifoundation.core.refine.wrench import rigid_task
    from manifoundation.core.robots import get_hand

    hand = get_hand("leap")
    mesh = trimesh.creation.box((0.06, 0.06, 0.06))
    pts, faces = trimesh.sample.sample_surface_even(mesh, 1500, seed=0)
    field = PointCloudField(pts, mesh.face_normals[faces])
    idx = [1093, 263, 1269, 1145]
    start = initialise(hand, field, pts[idx], mesh.face_normals[faces][idx])[0].pose
    return hand, mesh, field, rigid_task(np.array([0, 0, 1.0, 0, 0, 0]), np.zeros(3), 0.05), start
