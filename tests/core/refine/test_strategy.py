"""Approach alignment and the opposition-aware first roll (`manifoundation.core.refine.strategy`)."""

import numpy as np
import trimesh
from scipy.spatial.transform import Rotation

from manifoundation.core.refine.field import PointCloudField
from manifoundation.core.refine.initialise import distinct_opposition, opposition, rest_geometry
from manifoundation.core.refine.state import HandPose
from manifoundation.core.refine.strategy import align, pinch_roll


def test_pinch_roll_lays_the_opposition_across_the_thin_side(gripper):
    mesh = trimesh.creation.box(extents=[0.2, 0.03, 0.2])  # thin along y
    pts, faces = trimesh.sample.sample_surface(mesh, 2048, seed=0)
    cloud = PointCloudField(np.asarray(pts), np.asarray(mesh.face_normals[faces]))
    rng = np.random.default_rng(0)
    thumb, others = opposition(rest_geometry(gripper))
    for _ in range(5):
        # a start above the box (approach along −z), at a random roll
        quat = Rotation.from_euler("xz", [np.pi, rng.uniform(0, 2 * np.pi)]).as_quat()[[3, 0, 1, 2]]
        start = HandPose(np.array([0.0, 0.0, 0.3]), quat, np.asarray(gripper.rest, dtype=np.float64))
        roll = pinch_roll(gripper, cloud, start, np.zeros(3))
        pose = align(gripper, cloud, start, np.zeros(3), roll)
        u = Rotation.from_quat(pose.palm_quat[[1, 2, 3, 0]]).apply(others - thumb)
        assert abs(u[1]) / np.linalg.norm(u) > 0.99  # across the 3 cm side, not along the 20 cm ones


def test_opposition_picks_the_thumb_of_a_hand():
    from manifoundation.core.robots import get_hand

    hand = get_hand("allegro")
    rest = rest_geometry(hand)
    thumb, others = opposition(rest)
    assert np.allclose(thumb, rest.tips[3])  # allegro's thumb is its fourth fingertip
    assert np.allclose(others, rest.tips[:3].mean(axis=0))


def test_opposition_is_distinct_for_a_thumb_not_for_barrett():
    from manifoundation.core.robots import get_hand

    assert distinct_opposition(rest_geometry(get_hand("allegro")))
    assert distinct_opposition(rest_geometry(get_hand("panda_gripper")))
    assert distinct_opposition(rest_geometry(get_hand("leap")))
    assert not distinct_opposition(rest_geometry(get_hand("barrett")))  # three fingers at near-equal gaps
