"""Issue 59's acceptance test of a metric: the rates it reads, and its verdict."""

import numpy as np

from manifoundation.core.deformable.metrics import shape_score
from manifoundation.core.deformable.plasticine import make_plasticine
from manifoundation.core.deformable.procedures import Manipulation
from research.evaluation.deformable import DeformableCase, DeformableReport, MethodResult
from research.evaluation.separation import accepted, separation


def _report(random_reaches: int) -> DeformableReport:
    """Twenty cases on one body, its top point pressed 1 cm as the target; the replay reaches every one, random
    motions ``random_reaches`` of them, random points with the target's motion go 60 % of the way (rollouts made
    up from the clouds: the rule, not the simulator, is under test)."""
    body = make_plasticine("sphere", 0)
    start = body.points
    top = int(np.argmax(start[:, 2]))
    target = start.copy()
    target[top, 2] -= 0.01
    report = DeformableReport()
    for k in range(20):
        report.cases.append(DeformableCase("plasticine", "test_uo", body,
                                           Manipulation(np.array([top]), np.array([[0, 0, -0.01]]), "p"), target))
        report.results.append([
            MethodResult("ground_truth", shape_score("plasticine", start, target, target), 1),
            MethodResult("random_motion", shape_score("plasticine", start, target, target if k < random_reaches
                                                      else start + 0.0005), 2),
            MethodResult("random_target_motion", shape_score("plasticine", start, target,
                                                             start + 0.6 * (target - start)), 2),
        ])  # fmt: skip
    return report


def test_a_metric_that_separates_is_accepted_and_one_random_hit_too_many_is_not() -> None:
    rows = separation(_report(1), "plasticine", ("ground_truth", "random_motion", "random_target_motion", "x"))
    assert [(r.method, r.success, r.met) for r in rows] == [
        ("ground_truth", 100.0, True), ("random_motion", 5.0, True), ("random_target_motion", 0.0, True)]
    assert rows[0].paper_success == 100.0 and rows[2].closure < 0.7
    assert accepted(rows) is True
    assert accepted(separation(_report(2), "plasticine", ("ground_truth", "random_motion",
                                                          "random_target_motion"))) is False  # 10 % > 5 %
    assert accepted(rows[:2]) is None  # a criterion's method missing: not judged
