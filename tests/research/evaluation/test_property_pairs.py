"""The property pairs judged in the simulator: credit for reading the properties, none for ignoring them."""

from __future__ import annotations

import numpy as np

from manifoundation.core.deformable.slides import slide_candidates
from research.evaluation.deformable import DeformableCase
from research.evaluation.deformable_service import Proposal
from research.evaluation.property_pairs import (
    SENSITIVITY_PAIRS,
    figure_per_sample,
    property_figure,
    property_sensitivity,
)


def test_the_property_pairs_credit_an_answer_that_reads_the_properties_and_not_one_that_ignores_them() -> None:
    """Each member's own rollout is its target. A predictor that replays the manipulation only for the first
    member's properties (and drags one point nowhere for the other's) is better for the first member with its
    own properties and better for the second with the swapped ones; a property-blind replay ties on both."""
    first = SENSITIVITY_PAIRS["rope"][1]

    def reads_properties(case: DeformableCase) -> Proposal:
        m, points = case.manipulation, case.body.points
        if dict(case.body.properties) == first:
            return Proposal(points[m.contacts], m.motions, "network")
        return Proposal(points[m.contacts[:1]], np.zeros((1, 3)), "network")

    def blind(case: DeformableCase) -> Proposal:
        m = case.manipulation
        return Proposal(case.body.points[m.contacts], m.motions, "network")

    [reading] = property_sensitivity("rope", 1, seed=0, network=reads_properties)
    assert reading.matched_error is not None and reading.swapped_error is not None
    assert reading.matched_error[0] == 0.0 < reading.swapped_error[0]  # the replay on its own body: exact
    assert reading.swapped_error[1] == 0.0 < reading.matched_error[1]
    assert reading.matched_wins() == (1, 0)
    [ignoring] = property_sensitivity("rope", 1, seed=0, network=blind)
    assert ignoring.matched_wins() == (0, 2) and not ignoring.contacts_differ


def test_the_figure_credits_pulling_a_handkerchief_and_pushing_a_card_from_behind() -> None:
    """An answer that pulls the front corners of a pliable square and pushes a stiff one from behind (the paper's
    figure) reaches the slid square on both; the card's push, tried on the handkerchief, does not."""

    def paper(case: DeformableCase) -> Proposal:
        d = case.target[0] - case.body.points[0]
        name = "slide_front_pair" if case.body.properties["bending"] < 1e-3 else "slide_rear_one"
        [m] = [m for m in slide_candidates(case.body, d) if m.procedure == name]
        return Proposal(case.body.points[m.contacts], m.motions, "network")

    [(handkerchief, card)] = property_figure("cloth", 1, seed=0, network=paper)
    assert (handkerchief.name, card.name) == ("handkerchief", "card")
    assert handkerchief.own_reaches and card.own_reaches
    assert not handkerchief.other_reaches  # pushed from behind, it bunches up
    assert handkerchief.along > 0.3 > -0.3 > card.along
    assert not handkerchief.candidates["rear_one"] and card.candidates["rear_one"]
    assert handkerchief.candidates["front_pair"]


def _named_set(name: str):  # type: ignore[no-untyped-def]
    """An answer that always takes one named slide set (`slide_candidates`), whatever the properties."""

    def answer(case: DeformableCase) -> Proposal:
        d = case.target[0] - case.body.points[0]
        [m] = [m for m in slide_candidates(case.body, d) if m.procedure == f"slide_{name}"]
        return Proposal(case.body.points[m.contacts], m.motions, "network")

    return answer


def test_the_figure_per_sample_counts_each_answer_on_its_side_with_whether_it_reached() -> None:
    """Two answer functions on one square: its front corners and one rear point. The handkerchief follows only
    the pull (pushed from behind it bunches up), the card follows both; each answer is counted on its side."""
    handkerchief, card = figure_per_sample("cloth", 1, 0, [_named_set("front_pair"), _named_set("rear_one")])
    assert (handkerchief.name, card.name) == ("handkerchief", "card")
    assert (handkerchief.answers, handkerchief.reaches) == (2, 1)
    assert (handkerchief.ahead, handkerchief.ahead_reaching, handkerchief.behind, handkerchief.behind_reaching) == (
        1, 1, 1, 0)  # fmt: skip
    assert (card.answers, card.reaches, card.ahead_reaching, card.behind_reaching) == (2, 2, 1, 1)
