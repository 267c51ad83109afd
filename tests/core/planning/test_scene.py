import numpy as np
import trimesh

from manifoundation.core.planning import BoxObstacle, MeshObstacle, PointCloudObstacle, Pose, SupportPlane
from manifoundation.core.planning.scene import PLANE
from manifoundation.core.robots import get_hand
from tests.core.planning.conftest import scene_with


def test_box_hits_are_named_and_touching_the_table_is_allowed(block, wall):
    scene = scene_with(block, [wall], SupportPlane(0.0, tolerance=1e-3))
    assert scene.object_hits(Pose(np.array([0.0, 0, 0.1]))) == ["wall"]
    assert scene.object_hits(Pose(np.array([0.05, 0, 0.1]))) == []
    resting = Pose(np.array([0.1, 0, 0.03]))  # the block's bottom exactly on the table
    assert scene.object_free(resting) and scene.object_hits(resting) == []
    assert scene.object_hits(Pose(np.array([0.1, 0, 0.025]))) == [PLANE]


def test_point_cloud_obstacle_collides_by_its_occupied_voxels(block):
    rng = np.random.default_rng(0)
    # points on a 20 cm sphere's surface: the voxels are a shell, its inside stays free (no hull)
    d = rng.normal(size=(4000, 3))
    shell = 0.2 * d / np.linalg.norm(d, axis=1, keepdims=True)
    cloud = PointCloudObstacle(shell, resolution=0.02, name="shell")
    scene = scene_with(block, [cloud])
    assert scene.object_hits(Pose(np.array([0.2, 0, 0]))) == ["shell"]
    assert scene.object_free(Pose(np.zeros(3))) and scene.object_free(Pose(np.array([0.35, 0, 0])))


def test_a_closed_mesh_obstacle_contains_the_object(block):
    sphere = trimesh.creation.icosphere(subdivisions=2, radius=0.3)
    scene = scene_with(block, [MeshObstacle(np.asarray(sphere.vertices), np.asarray(sphere.faces), name="ball")])
    centre = Pose(np.zeros(3))
    assert scene.object_free(centre)  # the BVH sees no triangle: the fast test is a surface test ...
    assert scene.object_hits(centre) == ["ball"]  # ... the named one also tests containment
    assert scene.object_hits(Pose(np.array([0.3, 0, 0]))) == ["ball"]
    assert scene.object_hits(Pose(np.array([0.5, 0, 0]))) == []


def test_hand_hits_name_the_obstacle_its_links_meet(block):
    hand = get_hand("allegro")
    slab = BoxObstacle(np.array([0.3, 0.3, 0.02]), Pose(np.array([0.0, 0, 0.0])), "slab")
    scene = scene_with(block, [slab], SupportPlane(-0.2))
    rest = np.asarray(hand.rest)
    assert scene.hand_hits(hand, Pose(np.array([0.0, 0, 0.0])), rest) == ["slab"]
    assert scene.hand_hits(hand, Pose(np.array([0.0, 0, 0.5])), rest) == []
    assert scene.hand_hits(hand, Pose(np.array([0.5, 0, -0.2])), rest) == [PLANE]
