"""The pipeline's order of proposals: verified first, then (force closure) the better-balanced squeeze, then the
larger Ferrari–Canny ε."""

from __future__ import annotations

import numpy as np

from manifoundation.core.pipeline import ProposalOutput, QualityOutput
from manifoundation.core.pipeline.run import _rank


def _p(success: bool, epsilon: float | None) -> ProposalOutput:
    z = np.zeros((2, 3))
    quality = QualityOutput(success, True, "converged", 1, 0.0, 0.0, 0.0, 0.0, epsilon)
    return ProposalOutput(z, z, z, ["a", "b"], np.zeros(3), np.array([1.0, 0, 0, 0]), ["j"], np.zeros(1), quality)


def test_verified_first_then_the_larger_epsilon() -> None:
    ps = [_p(True, 0.02), _p(False, 0.5), _p(True, 0.1), _p(True, None), _p(True, float("nan")), _p(True, 0.05)]
    order = sorted(range(len(ps)), key=lambda i: _rank(ps[i]))
    assert order == [2, 5, 0, 3, 4, 1]


def test_verified_then_the_better_balanced_squeeze_then_epsilon() -> None:
    ps = [_p(True, 0.3), _p(True, 0.01), _p(False, 0.5), _p(True, 0.2)]
    for p, imbalance in zip(ps, (0.4, 0.1, 0.0, None), strict=True):
        p.squeeze_imbalance = imbalance
    assert sorted(range(len(ps)), key=lambda i: _rank(ps[i])) == [1, 0, 3, 2]
