"""The Table II protocol's ground truth from the data generator's grasp sampling (`research.evaluation.refinement`)."""

from types import SimpleNamespace

import numpy as np
import pytest

from manifoundation.core.refine.field import PointCloudField
from manifoundation.core.refine.verify import verify
from manifoundation.core.refine.wrench import characteristic_length, closure_task
from research.evaluation.refinement import SampledGroundTruth, evaluate, sampled_ground_truth


@pytest.fixture(scope="module")
def box_object(box):
    mesh, pts, nrm = box
    return SimpleNamespace(id="box-test", mesh=mesh, points=pts, normals=nrm, size=0.06, seed=0)


@pytest.fixture(scope="module")
def sampler(box_object, gripper):
    cloud = PointCloudField(box_object.points, box_object.normals)
    closure = closure_task(np.zeros(3), characteristic_length(box_object.points, np.zeros(3)))
    return SampledGroundTruth(gripper, box_object, cloud, closure, 0.5, seed=0, index=0, rounds=3, palms=8,
                              max_grasps=8)


def test_sampled_closure_ground_truth_passes_verify_with_positive_epsilon(sampler, box_object, gripper):
    found = sampled_ground_truth(sampler, "closure", 0, np.random.default_rng(0))
    assert found is not None
    pose, task, after = found
    assert task.closure and after >= 1
    ver = verify(gripper, pose, sampler.cloud, task, 0.5, box_object.mesh)
    assert ver.success, ver.failures
    assert ver.epsilon > 0


def test_sampled_task_ground_truth_passes_verify_for_its_own_wrench(sampler, box_object, gripper):
    found = sampled_ground_truth(sampler, "task", 0, np.random.default_rng(1))
    assert found is not None
    pose, task, _ = found
    assert not task.closure
    assert np.linalg.norm(task.target) == pytest.approx(1.0)
    ver = verify(gripper, pose, sampler.cloud, task, 0.5, box_object.mesh)
    assert ver.success, ver.failures


def test_next_grasp_starts_after_the_previous_one(sampler):
    first = sampled_ground_truth(sampler, "task", 0, np.random.default_rng(2))
    assert first is not None
    second = sampled_ground_truth(sampler, "task", first[2], np.random.default_rng(3))
    if second is not None:  # the sampler may have only one grasp left; when it has, it is another one
        assert second[2] > first[2]
        assert not np.allclose(second[0].palm_pos, first[0].palm_pos)


def test_spent_sampler_skips(box_object, gripper):
    cloud = PointCloudField(box_object.points, box_object.normals)
    spent = SampledGroundTruth(gripper, box_object, cloud, closure_task(np.zeros(3), 0.05), 0.5, 0, 0, rounds=0)
    assert sampled_ground_truth(spent, "closure", 0, np.random.default_rng(0)) is None


def test_evaluate_with_sampled_ground_truth_and_shared_cache(box_object, gripper, sampler):
    key = (gripper.name, box_object.id, 0, 0, 0.5)
    cache = {key: sampler}  # reuse the module's sampled grasps (as the CLI shares them between modes)
    report = evaluate(gripper, [box_object], "closure", 1, 0, cache=cache)
    assert report.ground_truth == "sampled"
    assert len(report.trials) + report.skipped == 1
    assert len(report.trials) == 1  # the sampler has a closure grasp (first test)
    with pytest.raises(ValueError):
        evaluate(gripper, [box_object], "closure", 1, 0, ground_truth="oracle")


def test_store_restores_sampled_ground_truths_without_sampling(box_object, gripper, sampler):
    sampler.candidate(0)  # make sure the module's sampler holds at least one round
    key = (gripper.name, box_object.id, 0, 0, 0.5)
    store = {key: (sampler.candidates, sampler.rounds_done)}
    first = evaluate(gripper, [box_object], "closure", 1, 0, store=store)
    assert len(first.trials) == 1
    # a store whose rounds are spent and hold no candidate: nothing is sampled, the grasp is skipped
    empty = {key: ([], 99)}
    skipped = evaluate(gripper, [box_object], "closure", 1, 0, store=empty)
    assert skipped.skipped == 1 and not skipped.trials
    assert empty[key] == ([], 99)
