"""Pinching palms across antipodal pairs (force-closure grasp sampling)."""

from __future__ import annotations

import numpy as np
import pytest
import torch
import trimesh
from scipy.spatial.transform import Rotation

from manifoundation.core.objects import make_object
from manifoundation.core.refine.field import PointCloudField
from manifoundation.core.refine.state import HandPose
from manifoundation.core.refine.verify import verify
from manifoundation.core.refine.wrench import characteristic_length, closure_task
from manifoundation.core.robots import get_hand
from research.data.checks import ObjectField
from research.data.pinch import antipodal_pairs, hand_opposition, sample_pinch_palms
from research.data.sampling import sample_grasps


def test_antipodal_pairs_of_a_box_span_its_sides() -> None:
    field = ObjectField(trimesh.creation.box((0.04, 0.08, 0.3)), seed=0)
    p1, p2 = antipodal_pairs(field, 400, 0.5, 0.1, np.random.default_rng(0))
    assert len(p1) > 50
    widths = np.sort(np.abs(p2 - p1), axis=1)[:, -1]  # a box's antipodal segments run along one axis
    assert np.all(np.isclose(widths, 0.04, atol=1e-6) | np.isclose(widths, 0.08, atol=1e-6))
    assert np.abs(p2 - p1).min(axis=1).max() < 1e-6


def test_pinch_palm_puts_the_hands_opposition_on_the_segment() -> None:
    hand = get_hand("allegro")
    field = ObjectField(trimesh.creation.cylinder(radius=0.03, height=0.2), seed=0)
    thumb, others, aperture = hand_opposition(hand)
    assert 0.05 < aperture < 0.2
    pos, quat = sample_pinch_palms(hand, field, 8, 0.5, np.random.default_rng(1))
    assert len(pos) > 0
    for p, q in zip(pos, quat, strict=True):
        rot = Rotation.from_quat(q[[1, 2, 3, 0]])
        a, b = rot.apply(thumb) + p, rot.apply(others) + p
        mid = 0.5 * (a + b)
        # midpoint on the (faceted) cylinder's axis, opposition axis across it (not along the caps)
        assert np.hypot(mid[0], mid[1]) < 0.005
        assert abs(a[2] - b[2]) < 1e-6


def test_no_pinch_when_the_object_is_wider_than_the_hand() -> None:
    field = ObjectField(trimesh.creation.box((0.3, 0.3, 0.3)), seed=0)
    pos, _ = sample_pinch_palms(get_hand("allegro"), field, 8, 0.5, np.random.default_rng(0))
    assert len(pos) == 0


@pytest.mark.slow
def test_closure_sampling_gives_verified_force_closure_grasps() -> None:
    torch.set_num_threads(1)
    hand = get_hand("allegro")
    obj = make_object("sphere", 0.07, seed=3)
    field = ObjectField(obj.mesh, seed=0)
    grasps = sample_grasps(hand, field, obj.size, np.random.default_rng(0), palms=8, max_grasps=4, closure_mu=0.5)
    assert grasps
    cloud = PointCloudField(obj.points, obj.normals)
    task = closure_task(np.zeros(3), characteristic_length(obj.points, np.zeros(3)))
    for g in grasps:
        ver = verify(hand, HandPose(g.palm_pos, g.palm_quat, g.q), cloud, task, 0.5, obj.mesh)
        assert ver.success, ver.failures
        assert ver.epsilon > 0
