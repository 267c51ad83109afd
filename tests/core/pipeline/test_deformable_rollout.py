"""Corrections through the simulator: a plasticine press answered with the target's displacement stops short
(the body springs back); corrected by rollouts it reaches the target, checked on the generator's own mesh."""

from __future__ import annotations

import numpy as np

from manifoundation.core.deformable.metrics import shape_score
from manifoundation.core.deformable.plasticine import make_plasticine
from manifoundation.core.deformable.procedures import plasticine_push
from manifoundation.core.deformable.simulate import simulate
from manifoundation.core.pipeline import SynthesisInput, TaskInput, run_pipeline
from manifoundation.core.robots import get_hand


def _press(kind: str, seed: int, corrections: int) -> tuple[object, np.ndarray, object]:
    body = make_plasticine(kind, seed)
    press = plasticine_push(body, np.random.default_rng(seed))
    target = simulate(body, press.contacts, press.motions).cloud
    inp = SynthesisInput(
        points=body.points, normals=body.normals, hand=get_hand("panda_gripper"),
        task=TaskInput("point_motion", motion=target - body.points), material="plasticine",
        properties=dict(body.properties), method="contacts", contacts=body.points[press.contacts], handless=True,
        num_contacts=len(press.contacts), simulate_rollout=True, rollout_corrections=corrections,
    )  # fmt: skip
    [answer] = run_pipeline(inp).proposals
    return body, target, answer


def test_a_press_by_the_targets_displacement_misses_and_corrected_reaches_it() -> None:
    body, target, open_loop = _press("composite", 3, corrections=0)
    assert not open_loop.quality.success and open_loop.quality.iterations == 0
    body, target, closed = _press("composite", 3, corrections=6)
    assert closed.quality.success and closed.quality.reason == "rollout_reached_target"
    assert 1 <= closed.quality.iterations <= 6
    assert not np.allclose(closed.contact_motions, open_loop.contact_motions)
    # the returned motions, applied to the generator's own mesh (not the service's rebuilt body)
    native = simulate(body, closed.contact_points, closed.contact_motions).cloud
    assert shape_score("plasticine", body.points, target, native).success
    np.testing.assert_allclose(closed.rollout_points, native, atol=1e-4)


def test_an_answer_that_reaches_its_target_spends_no_correction() -> None:
    _, _, answer = _press("ellipsoid", 1, corrections=6)
    assert answer.quality.success and answer.quality.iterations == 0
