import numpy as np
import pytest
import trimesh

from manifoundation.core.planning import BoxObstacle, PlanInput, PlanOptions, Pose, SupportPlane, plan_manipulation
from manifoundation.core.planning.scene import CollisionScene
from manifoundation.core.robots import get_hand


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


@pytest.fixture(scope="session")
def lifted(block):
    """A pure translation of the block, 15 cm along x at 20 cm above a table, carried by the Allegro hand."""
    mesh, pts, nrm = block
    inp = PlanInput(
        points=pts, normals=nrm, hand=get_hand("allegro"), start=Pose(np.array([-0.075, 0.0, 0.2])),
        waypoints=[Pose(np.array([0.075, 0.0, 0.2]))], support=SupportPlane(0.0),
        mesh_vertices=np.asarray(mesh.vertices), mesh_faces=np.asarray(mesh.faces),
        options=PlanOptions(translation_step=0.05, method="random_contacts", num_proposals=2, seed=1),
    )
    return inp, plan_manipulation(inp)
