"""The oracle predictor: the case's own valid grasps as heatmaps, through the pipeline's contact selection."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from manifoundation.core.objects import make_object
from manifoundation.core.robots import get_hand
from research.evaluation import testset
from research.evaluation.oracle import OraclePredictor
from research.evaluation.properties import _inputs, _select


def _case(grasp_points: list[list[int]], mask: np.ndarray | None = None) -> testset.TestCase:
    obj = make_object("box", 0.1, 0, num_points=1024)
    idx = np.array(grasp_points)  # (G, C) point indices of each valid grasp
    contacts, normals = obj.points[idx], obj.normals[idx]
    return testset.TestCase(
        split="test_uo", object_id=obj.id, label_hand="panda_gripper", points=obj.points, normals=obj.normals,
        mesh_vertices=np.asarray(obj.mesh.vertices), mesh_faces=np.asarray(obj.mesh.faces),
        motion=np.tile([0.0, 0.0, 0.02], (1024, 1)), mask=np.ones(1024, bool) if mask is None else mask,
        friction=0.5, articulated=False, joint_type="", joint_axis=np.zeros(3), joint_origin=np.zeros(3),
        joint_amount=0.0, grasp_contacts=contacts, grasp_normals=normals, grasp_forces=-0.5 * normals,
    )  # fmt: skip


def _opposite_pairs(points: np.ndarray, normals: np.ndarray, count: int) -> list[list[int]]:
    """``count`` pairs of points on opposite faces (normals within 10° of antiparallel)."""
    pairs: list[list[int]] = []
    for i in range(len(points)):
        j = int(np.argmin(normals @ normals[i]))
        if normals[j] @ normals[i] < -0.98 and all(i not in p for p in pairs):
            pairs.append([i, j])
        if len(pairs) == count:
            break
    return pairs


def test_samples_cycle_through_the_valid_grasps_and_select_their_contacts() -> None:
    obj = make_object("box", 0.1, 0, num_points=1024)
    case = _case(_opposite_pairs(obj.points, obj.normals, 2))
    hand = get_hand("panda_gripper")
    out = OraclePredictor([case]).predict([_inputs(case, hand)], num_samples=3)[0]
    assert out.heatmaps.shape == (3, 1024) and out.force_maps.shape == (3, 1024, 3)
    np.testing.assert_array_equal(out.heatmaps[0], out.heatmaps[2])  # G = 2: sample 2 is grasp 0 again
    assert not np.array_equal(out.heatmaps[0], out.heatmaps[1])
    assert case.grasp_contacts is not None
    for k in range(2):
        chosen = case.points[_select(case, out.heatmaps[k], out.force_maps[k], hand)]
        # each selected contact lies on one of grasp k's contacts (within the sample spacing)
        gap = np.linalg.norm(chosen[:, None] - case.grasp_contacts[k][None], axis=2).min(axis=1)
        assert len(chosen) == 2 and gap.max() < 0.02


def test_a_partial_mask_keeps_only_the_grasps_inside_it() -> None:
    obj = make_object("box", 0.1, 0, num_points=1024)
    pairs = _opposite_pairs(obj.points, obj.normals, 2)
    mask = np.ones(1024, bool)
    mask[pairs[1][0]] = False  # grasp 1 touches a masked-out point
    case = _case(pairs, mask)
    heat, _ = OraclePredictor.case_maps(case)
    assert len(heat) == 1
    assert heat[0, pairs[0]].min() > 0.9


def test_an_input_that_is_not_a_case_is_refused() -> None:
    obj = make_object("box", 0.1, 0, num_points=1024)
    case = _case(_opposite_pairs(obj.points, obj.normals, 1))
    other = dataclasses.replace(case, motion=-case.motion)
    with pytest.raises(KeyError):
        OraclePredictor([case]).predict([_inputs(other, get_hand("panda_gripper"))])


def _case_and_its_grasps_region() -> tuple[testset.TestCase, np.ndarray]:
    """A box case with two opposite-pair grasps, and the region (N,) bool its grasps' heat marks."""
    from research.data.grasp_sets import set_maps

    obj = make_object("box", 0.1, 0, num_points=1024)
    case = _case(_opposite_pairs(obj.points, obj.normals, 2))
    assert case.grasp_contacts is not None and case.grasp_normals is not None and case.grasp_forces is not None
    heat, _ = set_maps(case.points, case.normals, case.grasp_contacts, case.grasp_normals, case.grasp_forces,
                       float(np.ptp(case.points, axis=0).max()))  # fmt: skip
    return case, np.asarray((heat >= 0.5).any(axis=0))


def test_the_oracle_tops_its_region_where_a_random_point_rarely_would() -> None:
    from research.evaluation.properties import evaluate_properties

    case, own = _case_and_its_grasps_region()
    case.valid_region = own
    report = evaluate_properties([case], get_hand("panda_gripper"), OraclePredictor([case]), k=4)
    assert report.top_in_region == 1.0 and report.top_cases == 1
    assert report.region_share == pytest.approx(float(case.valid_region.mean()))
    assert 0.0 < report.region_share < 0.2 and report.empty_unmasked == 0.0


def test_the_top_point_is_judged_again_on_the_union_of_resampled_regions() -> None:
    from research.evaluation.properties import evaluate_properties

    case, own = _case_and_its_grasps_region()
    hand, oracle = get_hand("panda_gripper"), OraclePredictor([case])
    case.valid_region = ~own  # a data region the oracle's tops miss; a re-sampling that holds them
    report = evaluate_properties([case], hand, oracle, k=4, resampled={0: np.stack([~own, own])})
    assert report.top_in_region == 0.0 and report.top_in_union == 1.0 and report.union_sources == 2
    assert report.union_share == pytest.approx(1.0)
    elsewhere = np.zeros(1024, bool)
    elsewhere[np.flatnonzero(~own)[:10]] = True
    report = evaluate_properties([case], hand, oracle, k=4, resampled={0: elsewhere[None]})
    assert report.top_in_union == 0.0 and report.union_share == pytest.approx(10 / 1024)
