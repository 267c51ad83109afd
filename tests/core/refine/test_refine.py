import time

import numpy as np
import pytest

from manifoundation.core.refine.field import PointCloudField
from manifoundation.core.refine.initialise import initialise
from manifoundation.core.refine.refine import Cancelled, RefineConfig, refine
from manifoundation.core.refine.verify import verify
from manifoundation.core.refine.wrench import closure_task, rigid_task

CONTACTS = np.array([[0.02, 0, 0], [-0.02, 0, 0]])
NORMALS = np.array([[1.0, 0, 0], [-1, 0, 0]])


@pytest.fixture(scope="module")
def setup(box, gripper):
    mesh, pts, nrm = box
    field = PointCloudField(pts, nrm)
    start = initialise(gripper, field, CONTACTS, NORMALS)[0]
    return mesh, field, start


def test_initialisation_fits_the_gripper_across_the_box(setup, gripper):
    _, _, start = setup
    assert start.rms < 0.03
    assert start.pose.q[0] == pytest.approx(gripper.rest[0])


def test_two_finger_antipodal_box_closure(setup, gripper):
    mesh, field, start = setup
    task = closure_task(np.zeros(3), 0.05)
    res = refine(gripper, field, task, start.pose, 0.5, RefineConfig(history=True))
    assert res.converged, res.reason
    assert res.residual_norm < 1e-6 and res.max_tip_distance < 5e-3
    assert len(res.history) == res.iterations
    ver = verify(gripper, res.pose, field, task, 0.5, mesh)
    assert ver.success, ver.failures
    assert ver.epsilon > 0


def test_unreachable_wrench_is_a_clear_non_converged_result(setup, gripper):
    _, field, start = setup
    task = rigid_task(np.array([1.0, 0, 0, 0, 0, 0]), np.zeros(3), 0.05)
    res = refine(gripper, field, task, start.pose, 0.5, RefineConfig(max_iterations=8, max_normal_force=0.05))
    assert not res.converged
    assert res.reason in ("max_iterations", "stalled")
    assert res.residual_norm > 0.5


def test_deadline_and_cancel(setup, gripper):
    _, field, start = setup
    task = closure_task(np.zeros(3), 0.05)
    res = refine(gripper, field, task, start.pose, 0.5, deadline=time.monotonic() - 1)
    assert res.reason == "deadline" and not res.converged and res.iterations == 0
    with pytest.raises(Cancelled):
        refine(gripper, field, task, start.pose, 0.5, should_cancel=lambda: True)


def test_masked_convergence_also_applies_the_verifications_point_test(setup, gripper):
    mesh, field, start = setup
    masked = PointCloudField(field.points, field.normals, np.abs(field.points[:, 0]) > 0.0199)  # the x faces
    task = closure_task(np.zeros(3), 0.05)
    res = refine(gripper, masked, task, start.pose, 0.5, RefineConfig(), tip_field=masked.region_distance)
    assert res.converged, res.reason
    assert np.max(masked.region_point_distance(res.tips)) < RefineConfig().region_point_tol
    assert verify(gripper, res.pose, masked, task, 0.5, mesh).success
    unattainable = RefineConfig(region_point_tol=1e-9, max_iterations=15)  # no contact lies exactly on a sample
    assert not refine(gripper, masked, task, start.pose, 0.5, unattainable, tip_field=masked.region_distance).converged


@pytest.fixture(scope="module")
def leap_pushed(leap_on_a_box):
    """The LEAP hand of ``leap_on_a_box`` pushed 4 cm into the cube: (hand, mesh, field, task, pose)."""
    from manifoundation.core.refine.state import HandPose

    hand, mesh, field, task, start = leap_on_a_box
    inward = -start.palm_pos / np.linalg.norm(start.palm_pos)
    return hand, mesh, field, task, HandPose(start.palm_pos + 0.04 * inward, start.palm_quat, start.q)


def test_a_hand_stuck_in_the_object_stops_early_with_the_same_iterates(leap_pushed):
    """A LEAP hand pushed 4 cm into a box from its initial pose: its guards stay > 1 mm deep and the merit stops
    falling, so it stops after the stuck window (3 iterations) instead of the stall window (8); every iterate up
    to there is the one the run without the rule takes."""
    hand, _, field, task, pushed = leap_pushed
    cfg = RefineConfig(history=True, touch_weight=1.0)  # the full merit from the start: the rule alone (below:
    # closing the fingers first frees this hand)
    stuck = refine(hand, field, task, pushed, 0.8, cfg)
    patient = refine(hand, field, task, pushed, 0.8, RefineConfig(history=True, touch_weight=1.0,
                                                                  stuck_penetration=np.inf))  # fmt: skip
    assert stuck.reason == "stalled" and not patient.converged
    assert stuck.iterations < patient.iterations
    kept = len(stuck.history)  # the stopping iteration is not recorded
    assert kept == stuck.iterations - 1 and kept >= cfg.stuck_window
    assert [r.merit for r in stuck.history] == [r.merit for r in patient.history[:kept]]
    final = patient.history[kept].merit  # the iterate it stopped at: the same one
    assert stuck.penetration > cfg.stuck_penetration
    assert final > (1 - cfg.stuck_tolerance) * stuck.history[kept - cfg.stuck_window].merit


def test_a_refused_step_that_would_repeat_ends_the_attempt(setup, gripper):
    """With the trust region unchanged after a refusal (here: fixed), the next step is the same step (same
    linearisation, deterministic solver) and would be refused again, so the attempt ends there."""
    from manifoundation.core.refine.state import linearise
    from manifoundation.core.refine.step import StepParams, solve_step

    _, field, start = setup
    task = rigid_task(np.array([1.0, 0, 0, 0, 0, 0]), np.zeros(3), 0.05)
    cfg = RefineConfig(max_iterations=40, max_normal_force=0.05, adaptive=False, history=True)
    res = refine(gripper, field, task, start.pose, 0.5, cfg)
    assert res.reason == "stalled" and res.iterations == len(res.history) + 1 < cfg.max_iterations
    assert all(r.accepted for r in res.history)  # it ended at the first refusal, not after repeating it
    n = 6 + len(res.pose.q)
    trust = np.concatenate([np.full(3, cfg.trust_translation), np.full(3, cfg.trust_rotation),
                            np.full(n - 6, cfg.trust_joint)])  # fmt: skip
    params = StepParams(trust=trust, trust_force=cfg.trust_force, tip_weight=cfg.tip_weight, penalty=cfg.penalty)
    lin = linearise(gripper, res.pose, field, task, 0.5, cfg.max_normal_force)
    first, again = solve_step(lin, params), solve_step(lin, params)
    np.testing.assert_array_equal(first.delta, again.delta)  # the step it would have tried next


def test_closing_the_fingers_first_frees_the_hand_stuck_in_the_box(leap_pushed):
    """The same pushed LEAP hand: with the wrench residual weighed down while a tip is more than 3 mm off, the
    fingers close first and the refinement ends in a grasp that the exact mesh verifies; with the full residual
    from the start it stays stuck."""
    hand, mesh, field, task, pushed = leap_pushed
    closing = refine(hand, field, task, pushed, 0.8, RefineConfig(history=True))
    full = refine(hand, field, task, pushed, 0.8, RefineConfig(touch_weight=1.0))
    assert RefineConfig().touch_weight < 1.0
    assert not full.converged
    assert closing.converged
    assert verify(hand, closing.pose, field, task, 0.8, mesh).success
    tips = [r.max_tip_distance for r in closing.history]
    assert min(tips) < RefineConfig().touch_distance  # the fingers did close
