"""The property pairs judged in the simulator: credit for reading the properties, none for ignoring them."""

from __future__ import annotations

import numpy as np

from models.evaluation.deformable import DeformableCase
from models.evaluation.property_pairs import SENSITIVITY_PAIRS, property_sensitivity


def test_the_property_pairs_credit_an_answer_that_reads_the_properties_and_not_one_that_ignores_them() -> None:
    """Each member's own rollout is its target. A predictor that replays the manipulation only for the first
    member's properties (and drags one point nowhere for the other's) is better for the first member with its
    own properties and better for the second with the swapped ones; a property-blind replay ties on both."""
    first = SENSITIVITY_PAIRS["rope"][1]

    def reads_properties(case: DeformableCase) -> tuple[np.ndarray, np.ndarray, str]:
        m, points = case.manipulation, case.body.points
        if dict(case.body.properties) == first:
            return points[m.contacts], m.motions, "network"
        return points[m.contacts[:1]], np.zeros((1, 3)), "network"

    def blind(case: DeformableCase) -> tuple[np.ndarray, np.ndarray, str]:
        m = case.manipulation
        return case.body.points[m.contacts], m.motions, "network"

    [reading] = property_sensitivity("rope", 1, seed=0, network=reads_properties)
    assert reading.matched_error is not None and reading.swapped_error is not None
    assert reading.matched_error[0] == 0.0 < reading.swapped_error[0]  # the replay on its own body: exact
    assert reading.swapped_error[1] == 0.0 < reading.matched_error[1]
    assert reading.matched_wins() == (1, 0)
    [ignoring] = property_sensitivity("rope", 1, seed=0, network=blind)
    assert ignoring.matched_wins() == (0, 2) and not ignoring.contacts_differ
