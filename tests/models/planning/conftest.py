import numpy as np
import pytest
import trimesh

from models.planning import BoxObstacle, Pose
from models.planning.scene import CollisionScene


@pytest.fixture(scope="session")
def block():
    """A 4 x 6 x 6 cm box object centred on its frame: mesh, 512 surface points, outward normals."""
    mesh = trimesh.creation.box(extents=[0.04, 0.06, 0.06])
    pts, faces = trimesh.sample.sample_surface(mesh, 512, seed=0)
    return mesh, np.asarray(pts), np.asarray(mesh.face_normals[faces])


@pytest.fixture(scope="session")
def wall():
    """A 2 cm thick wall at x = 0, 40 cm wide (y), 30 cm tall, standing on z = 0."""
    return BoxObstacle(np.array([0.02, 0.4, 0.3]), Pose(np.array([0.0, 0.0, 0.15])), "wall")


def scene_with(block, obstacles, support=None) -> CollisionScene:
    mesh = block[0]
    return CollisionScene(obstacles, support, np.asarray(mesh.vertices), np.asarray(mesh.faces))
