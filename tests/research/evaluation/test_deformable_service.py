"""The evaluation's service methods: K answers from `run_pipeline`, judged on the case's own body."""

from pathlib import Path

import numpy as np
import pytest

from manifoundation.core.deformable.metrics import shape_score
from manifoundation.core.deformable.simulate import simulate
from manifoundation.core.robots import get_hand
from research.data.deformable_generate import DeformableDataConfig
from research.evaluation.deformable import build_cases, evaluate_case
from research.evaluation.deformable_service import service_answers

WEIGHTS = Path(__file__).resolve().parents[3] / "manifoundation" / "core" / "weights" / "cpu1k"


def test_network_samples_is_the_fraction_of_the_services_k_answers_that_reach_the_target() -> None:
    """Recomputed here from the answers' own rollouts (simulate + shape_score on the case's body), not from the
    method's result; the shipped weights' held-out rope answers mostly succeed (measured 0.9 of 8 per case)."""
    from manifoundation.core.network import ContactPredictor

    predictor = ContactPredictor.from_checkpoint(WEIGHTS)
    service = service_answers(predictor, get_hand("panda_gripper"), seed=0, proposals=3)
    cases = build_cases("rope", "test_uo", 2, seed=0, data=DeformableDataConfig(seed=5))
    rates = []
    for case in cases:
        answers = service["network_samples"](case)
        assert len(answers) == 3
        own = [shape_score("rope", case.body.points, case.target, simulate(case.body, p, m).cloud).success
               for p, m, *_ in answers]  # fmt: skip
        # the output holds sample 0's maps: only the first answer carries the head's own motion estimate
        assert (answers[0].estimate is not None) == (answers[0].source == "network")
        assert all(a.estimate is None for a in answers[1:])
        [result] = evaluate_case(case, ("network_samples",), 2, np.random.default_rng(0), service=service)
        assert result.success == pytest.approx(np.mean(own))
        assert result.score.success == own[0]
        assert np.isfinite(result.readback) == (result.source == "network")
        rates.append(result.success)
    assert np.mean(rates) >= 0.5


def test_checked_methods_return_the_services_first_answer_and_need_their_callables() -> None:
    [case] = build_cases("rope", "test_uo", 1, seed=0, data=DeformableDataConfig(seed=5))
    service = service_answers(None, get_hand("panda_gripper"), seed=0, proposals=2)
    assert set(service) == {"random_checked"}  # without a predictor the network's methods are not offered
    [result] = evaluate_case(case, ("random_checked",), 2, np.random.default_rng(0), service=service)
    assert result.source == "random" and result.contacts == 2 and result.rate is None
    with pytest.raises(ValueError, match="network_checked"):
        evaluate_case(case, ("network_checked",), 2, np.random.default_rng(0), service=service)
    with pytest.raises(ValueError, match="proposals"):
        service_answers(None, get_hand("panda_gripper"), seed=0, proposals=0)
