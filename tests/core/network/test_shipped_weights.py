"""The shipped weights (manifoundation/core/weights/cpu1k) on an object they were not trained on: a heatmap that marks
places,
and contacts selected from it that lie on the object."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import trimesh

from manifoundation.core.network import ContactPredictor, NetworkInput, select_contacts
from manifoundation.core.objects import make_object
from manifoundation.core.robots import Hand, get_hand
from manifoundation.core.robots.registry import urdf_source
from manifoundation.core.robots.urdf import parse_urdf
from research.data.generate import object_split
from research.data.labels import rigid_point_motion

WEIGHTS = Path(__file__).resolve().parents[3] / "manifoundation" / "core" / "weights" / "cpu1k"


def _held_out_object():  # type: ignore[no-untyped-def]
    """The first procedural composite whose id the data sets' split puts among the test objects."""
    for seed in range(100):
        obj = make_object("composite", 0.12, seed, 2048)
        if object_split(obj.id, 0.15) == "test":
            return obj
    raise AssertionError("no held-out object among 100 seeds")


def _allegro_as_trained() -> Hand:
    """Allegro as these weights saw it in training: built from its URDF's collision boxes and tip spheres (the
    service now builds it from its real, visual meshes; its hand input changed with them, and the network issue
    retrains)."""
    served = get_hand("allegro")
    source = urdf_source("allegro")
    assert source is not None
    return Hand(parse_urdf(source[0]), name="allegro", fingertips=served.fingertip_links,
                tip_offsets=served.tip_offsets, rest=served.rest, approach_axis=served.approach_axis)  # fmt: skip


def test_shipped_heatmap_on_a_held_out_object_is_not_flat_and_its_contacts_lie_on_it() -> None:
    predictor = ContactPredictor.from_checkpoint(WEIGHTS)
    assert predictor.is_trained
    obj, hand = _held_out_object(), _allegro_as_trained()
    # a tilt: 1 cm up and 0.2 rad about a horizontal axis (the data's motions are mostly such rotations; on pure
    # translations and turns about the vertical these weights' maps are weaker, see their README)
    motion = rigid_point_motion(obj.points, obj.points.mean(axis=0), np.array([0.0, 0.0, 0.01]), np.array([0.2, 0, 0]))
    inp = NetworkInput(obj.points, obj.normals, motion, np.ones(len(obj.points), bool), {"friction": 0.6},
                       hand.surface_points, hand.surface_normals, hand.name)  # fmt: skip
    out = predictor.predict([inp], num_samples=4, seed=0)[0]
    contrast = out.heatmaps.max(axis=1) - np.median(out.heatmaps, axis=1)
    assert (contrast >= 0.1).all(), contrast  # the selection's flat-heatmap rule: none falls back to random
    for k in range(4):
        sel = select_contacts(obj.points, out.heatmaps[k], out.force_maps[k], None, hand.num_fingertips)
        assert 1 <= len(sel) <= hand.num_fingertips
        dist = np.abs(trimesh.proximity.signed_distance(obj.mesh, sel.points))
        assert dist.max() < 1e-3


@pytest.mark.parametrize(("material", "least"), [("rope", 4), ("cloth", 3)])
def test_shipped_weights_answer_held_out_deformables_themselves_and_reach_their_targets(
    material: str, least: int
) -> None:
    """Their deformable head on six cases of bodies no training saw (the evaluation's own cases): answers from the
    network's own peaks (not the most-moved-points fallback) reach their targets in the simulator by the paper's
    metric in at least four (rope) and three (cloth) (measured 2026-12-05: rope 5 of 5 own answers, cloth 4 of 6;
    2026-12-06, round 16: rope 6 of 6, cloth 4 of 5;
    the round-12 weights, without verified labels, the motion gain and the read-out loss: rope 3 of 4, cloth 0 of
    4)."""
    from research.data.deformable_generate import DeformableDataConfig
    from research.evaluation.deformable import build_cases, evaluate_case, pipeline_network

    predictor = ContactPredictor.from_checkpoint(WEIGHTS)
    answer = pipeline_network(predictor, get_hand("panda_gripper"), seed=0)
    cases = build_cases(material, "test_uo", 6, seed=0, data=DeformableDataConfig(seed=5))
    results = [evaluate_case(c, ("network",), 2, np.random.default_rng(0), answer)[0] for c in cases]
    own = [r.score.success for r in results if r.source == "network"]
    assert sum(own) >= least, [(r.source, r.score) for r in results]


def _own_square_answers(member: int) -> list[tuple[float, bool]]:
    """The shipped weights' own-peak answers to the property figure's first eight squares (seed 0), each slid by
    0.3 of its size, asked of one member (0 the handkerchief, 1 the card): for each answer its contacts' mean
    along d (× size; + ahead of the centre) and whether its rollout reaches the slid square."""
    from manifoundation.core.deformable.simulate import simulate
    from manifoundation.core.deformable.slides import along_and_across
    from research.evaluation.deformable import pipeline_network
    from research.evaluation.property_pairs import figure_cases

    answer = pipeline_network(ContactPredictor.from_checkpoint(WEIGHTS), get_hand("panda_gripper"), seed=0)
    own = []
    for cases in figure_cases("cloth", 8, 0):
        case = cases[member]
        proposal = answer(case)
        if proposal.source != "network":
            continue
        body, d = case.body, case.manipulation.motions[0]
        along, _ = along_and_across(proposal.points, d, origin=body.points.mean(axis=0))
        reached = simulate(body, proposal.points, proposal.motions).reaches(body, case.target)
        own.append((float(along.mean()) / body.size, reached))
    return own


def test_shipped_weights_pull_a_slid_handkerchief_from_its_front() -> None:
    """The paper's property figure, handkerchief side. Every answer from the network's own peaks puts its
    contacts' mean ahead of the centre along d and reaches the slid square in the simulator, and there are at
    least four such answers (measured 2026-12-06: round 16, 8 own answers, all ahead and reaching; round 15, 6,
    all ahead and reaching; round 14, 4 own answers, the two behind the centre, −0.37 and −0.67 of the size,
    folding the square)."""
    own = _own_square_answers(0)
    assert len(own) >= 4, own
    assert all(ahead > 0 and reached for ahead, reached in own), own


def test_shipped_weights_push_a_slid_card_from_its_rear() -> None:
    """The paper's property figure, card side: the same squares and slides as a card (stretch 10⁵ N/m, bending
    10⁻² N·m). At least six answers from the network's own peaks put their contacts' mean behind the centre along
    d — the side the handkerchief is never taken from — and every one of those reaches the slid card in the
    simulator (measured 2026-12-06: round 16, 8 own answers, all behind, −0.30 to −0.59 of the size, and
    reaching; round 15, 7 own answers, all ahead, +0.51 to +0.65 — pulled from the front like the handkerchief)."""
    own = _own_square_answers(1)
    behind = [reached for along, reached in own if along < 0]
    assert len(behind) >= 6 and all(behind), own
