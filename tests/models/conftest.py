"""Fixtures shared by the science tests (refinement and its evaluation): a box, the Panda gripper."""

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
    from models.robots import get_hand

    return get_hand("panda_gripper")
