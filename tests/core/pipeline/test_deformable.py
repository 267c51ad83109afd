from dataclasses import replace

import numpy as np
import pytest

from manifoundation.core.deformable.procedures import rope_drag
from manifoundation.core.deformable.rope import make_rope
from manifoundation.core.pipeline import InvalidInput, SynthesisInput, TaskInput, run_pipeline
from manifoundation.core.robots import get_hand


@pytest.fixture(scope="module")
def gripper():  # type: ignore[no-untyped-def]
    return get_hand("panda_gripper")


def _request(hand, task: TaskInput, method: str = "random_contacts") -> SynthesisInput:  # type: ignore[no-untyped-def]
    rope = make_rope(seed=0)
    return SynthesisInput(points=rope.points, hand=hand, task=task, normals=rope.normals, material="rope",
                          properties=rope.properties, method=method, num_proposals=2, seed=1)  # fmt: skip


def test_deformable_answer_is_contacts_with_the_tasks_motion_and_named_fingertips(gripper) -> None:  # type: ignore[no-untyped-def]
    rope = make_rope(seed=0)
    m = rope_drag(rope, np.random.default_rng(0))
    motion = np.zeros_like(rope.points)
    motion[m.contacts] = m.motions
    motion += np.linspace(0, 0.01, len(motion))[:, None]  # every point has its own motion
    out = run_pipeline(_request(gripper, TaskInput("point_motion", motion=motion)))
    for p in out.proposals:
        idx = [int(np.argmin(np.linalg.norm(rope.points - c, axis=1))) for c in p.contact_points]
        np.testing.assert_allclose(p.contact_motions, motion[idx])
        assert sorted(p.fingertips) == sorted(gripper.fingertip_links)
        assert p.quality.reason == "deformable_open_loop" and not p.quality.success


def test_unordered_targets_are_registered_back_to_their_motion(gripper) -> None:  # type: ignore[no-untyped-def]
    rope = make_rope(seed=0)
    motion = np.tile([0.02, -0.01, 0.0], (len(rope.points), 1))
    shuffled = (rope.points + motion)[np.random.default_rng(3).permutation(len(rope.points))]
    out = run_pipeline(_request(gripper, TaskInput("target_points", targets=shuffled, correspondence="unknown")))
    np.testing.assert_allclose(out.proposals[0].contact_motions, motion[:2], atol=1e-9)


def test_direct_grasp_is_refused_for_a_deformable(gripper) -> None:  # type: ignore[no-untyped-def]
    task = TaskInput("point_motion", motion=np.zeros((len(make_rope(seed=0).points), 3)))
    with pytest.raises(InvalidInput, match="method"):
        run_pipeline(_request(gripper, task, method="direct_grasp"))


def test_with_a_rollout_the_most_moved_points_compete_with_the_networks_contacts(gripper) -> None:  # type: ignore[no-untyped-def]
    """The shipped network (trained on rigid objects) puts a peak on this rope; judged in the simulator, the
    most-moved points are one more candidate, and the answer that reaches the target is the one returned."""
    from manifoundation.core.deformable.simulate import simulate
    from manifoundation.core.network.inference import ContactPredictor

    predictor = ContactPredictor.from_checkpoint("manifoundation/core/weights/cpu1k")
    rope = make_rope(seed=2, length=0.5)
    drag = rope_drag(rope, np.random.default_rng(2))
    motion = simulate(rope, drag.contacts, drag.motions).cloud - rope.points
    asked = SynthesisInput(points=rope.points, hand=gripper, task=TaskInput("point_motion", motion=motion),
                           normals=rope.normals, material="rope", properties=rope.properties, method="network",
                           num_proposals=1, seed=0)  # fmt: skip
    [open_loop] = run_pipeline(asked, predictor).proposals
    assert open_loop.contact_source == "network"  # the network's own contacts, not its flat-map fallback
    [judged] = run_pipeline(replace(asked, simulate_rollout=True), predictor).proposals
    assert judged.quality.success and judged.quality.reason == "rollout_reached_target"
    assert judged.contact_source in ("network", "motion_fallback")
