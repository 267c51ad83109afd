"""Evaluation plumbing: request building for every method, the table, contact-set comparison."""

from __future__ import annotations

import numpy as np

from manifoundation.core.objects import make_object
from manifoundation.core.robots import get_hand
from research.evaluation.properties import _same
from research.evaluation.protocol import METHODS, MethodResult, synthesis_input, table
from research.evaluation.testset import TestCase


def _case(articulated: bool) -> TestCase:
    obj = make_object("box", 0.1, 0, num_points=128)
    mask = np.ones(128, dtype=bool)
    mask[:10] = False
    return TestCase(
        split="test_uo", object_id=obj.id, label_hand="allegro", points=obj.points, normals=obj.normals,
        mesh_vertices=np.asarray(obj.mesh.vertices), mesh_faces=np.asarray(obj.mesh.faces),
        motion=np.tile([0.01, 0.0, 0.0], (128, 1)), mask=mask, friction=0.5, articulated=articulated,
        joint_type="revolute" if articulated else "", joint_axis=np.array([0, 0, 1.0]),
        joint_origin=np.array([0.05, 0.05, 0.0]), joint_amount=0.2,
    )  # fmt: skip


def test_requests_for_every_method() -> None:
    hand = get_hand("panda_gripper")
    for articulated in (False, True):
        case = _case(articulated)
        for m in METHODS:
            inp = synthesis_input(case, hand, m, 4, 0, 50)
            assert inp.method in ("network", "random_contacts", "direct_grasp")
            assert inp.refine == (m != "network_no_refine")
            assert inp.properties == {"friction": 0.5}
            assert inp.mask is not None and not inp.mask[:10].any()
            assert (inp.task.kind == "joint_motion") == articulated
            assert (inp.joint is not None) == articulated


def test_table_and_modes() -> None:
    rows = [MethodResult("network", "leap", "test_uo", 3, 4), MethodResult("direct_grasp", "leap", "test_uo", 1, 4)]
    text = table(rows)
    assert "75.0% (3/4)" in text and "25.0% (1/4)" in text
    rows[0].fallbacks = 2  # a network success from random contacts must not pass for a network result
    assert "75.0% (3/4, 2 fallback)" in table(rows)
    pts = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0.0]])
    assert _same(np.array([0, 1]), np.array([1, 0]), pts, 0.1)
    assert not _same(np.array([0, 1]), np.array([0, 2]), pts, 0.1)
