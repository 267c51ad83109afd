"""The simulated grasp test in the pipeline (real MuJoCo): "search" judges each candidate and draws more until enough
hold, the best returned in physics order; "check" (the service's default) tests each returned proposal once."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import trimesh

from manifoundation.core.physics import PhysicsResult
from manifoundation.core.pipeline import (
    PhysicsMode,
    ProposalOutput,
    QualityOutput,
    SynthesisInput,
    TaskInput,
    physics_mode,
    run_pipeline,
)
from manifoundation.core.pipeline.physics_search import best_by_physics, enough_held
from manifoundation.core.robots import get_hand

WEIGHTS = Path(__file__).resolve().parents[3] / "manifoundation" / "core" / "weights" / "cpu1k"


def _box() -> tuple[np.ndarray, np.ndarray, trimesh.Trimesh]:
    box = trimesh.creation.box(extents=[0.04, 0.06, 0.06])
    pts, faces = trimesh.sample.sample_surface_even(box, 800, seed=0)
    return np.asarray(pts), np.asarray(box.face_normals[faces]), box


def _inp(**kw: object) -> SynthesisInput:
    pts, nrm, box = _box()
    base: dict[str, object] = dict(
        points=pts, normals=nrm, hand=get_hand("panda_gripper"), task=TaskInput("force_closure"),
        mesh_vertices=np.asarray(box.vertices), mesh_faces=np.asarray(box.faces), simulate="search",
    )  # fmt: skip
    base.update(kw)
    return SynthesisInput(**base)  # type: ignore[arg-type]


@pytest.mark.parametrize("mode", ["off", "check"])
def test_candidates_are_sixteen_or_as_many_as_asked(mode: PhysicsMode) -> None:
    assert [_inp(num_proposals=k).candidates for k in (1, 2, 16, 20)] == [16, 16, 16, 20]
    assert [_inp(num_proposals=k, simulate=mode).candidates for k in (1, 3)] == [1, 3]


def test_a_grasp_that_holds_ends_the_search_at_once() -> None:
    fractions: list[float] = []
    out = run_pipeline(_inp(method="contacts", contacts=np.array([[0.02, 0, 0], [-0.02, 0, 0]])),
                       progress=lambda stage, f: fractions.append(f) if stage == "verification" else None)  # fmt: skip
    (best,) = out.proposals
    assert best.physics is not None and best.physics.success and len(best.physics.trials) == 6
    assert best.physics.object_pieces == "hull"
    assert fractions == [1 / 16]  # one candidate of sixteen refined, judged, enough
    assert out.timings["physics"] > 0


def test_without_a_grasp_that_holds_every_candidate_is_tried_and_the_answer_lists_every_push() -> None:
    # both pads asked onto the same face and left unrefined: nothing opposes them, nothing holds
    fractions: list[float] = []
    out = run_pipeline(_inp(method="contacts", contacts=np.array([[0.02, 0.01, 0], [0.02, -0.01, 0]]), refine=False),
                       progress=lambda stage, f: fractions.append(f) if stage == "verification" else None)  # fmt: skip
    (best,) = out.proposals
    assert fractions[-1] == 1.0 and len(fractions) == 16
    assert best.physics is not None and not best.physics.success
    # searching stopped at the first push that moved it; the answer lists all six
    assert best.physics.reason == "moved"
    assert [t.direction for t in best.physics.trials] == ["-x", "+x", "-y", "+y", "-z", "+z"]


def test_a_gripper_asked_to_hold_gets_opposed_pads_and_the_held_ones_first() -> None:
    from manifoundation.core.network import ContactPredictor

    predictor = ContactPredictor.from_checkpoint(str(WEIGHTS))
    out = run_pipeline(_inp(method="network", num_proposals=2), predictor=predictor)
    assert len(out.proposals) == 2
    for p in out.proposals:
        assert p.contact_source in ("opposed", "random_fallback") and p.physics is not None
    held = [p.physics is not None and p.physics.success for p in out.proposals]
    assert held == sorted(held, reverse=True)


def _judged(verified: bool, held: bool | None) -> ProposalOutput:
    p = ProposalOutput(np.zeros((2, 3)), np.zeros((2, 3)), np.zeros((2, 3)), ["a", "b"], np.zeros(3),
                       np.array([1.0, 0, 0, 0]), ["j"], np.zeros(1),
                       QualityOutput(verified, verified, "converged", 1, 0.0, 0.0, 0.0, 0.0, 0.1))  # fmt: skip
    if held is not None:
        p.physics = PhysicsResult(held, [], "held" if held else "moved", 0.0, [0.0, 0.0], 2, np.zeros(1), np.zeros(1))
    return p


@pytest.mark.parametrize(("wanted", "expected"), [(1, [2]), (2, [2, 1]), (4, [2, 1, 0, 3])])
def test_best_by_physics_takes_held_and_verified_then_held_then_verified(wanted: int, expected: list[int]) -> None:
    ps = [_judged(True, False), _judged(False, True), _judged(True, True), _judged(True, None)]
    assert best_by_physics(ps, wanted) == [ps[i] for i in expected]
    assert enough_held(ps, 1) and not enough_held(ps, 2)  # held but not verified is no success: search on


def test_the_services_default_checks_what_it_returns_and_an_unheld_proposal_is_no_success() -> None:
    # both pads on one face, unrefined: geometric verification is not asked (refine off) but the test runs
    fractions: list[float] = []
    contacts = np.array([[0.02, 0.01, 0], [0.02, -0.01, 0]])
    out = run_pipeline(_inp(method="contacts", contacts=contacts, refine=False, simulate="check"),
                       progress=lambda stage, f: fractions.append(f) if stage == "verification" else None)  # fmt: skip
    (p,) = out.proposals
    assert fractions == [1.0]  # one candidate: a check draws no more
    assert p.physics is not None and not p.physics.success and len(p.physics.trials) == 6
    held = run_pipeline(_inp(method="contacts", contacts=np.array([[0.02, 0, 0], [-0.02, 0, 0]]), simulate="check"))
    (q,) = held.proposals
    assert q.physics is not None and q.physics.success and q.quality.success
    off = run_pipeline(_inp(method="contacts", contacts=np.array([[0.02, 0, 0], [-0.02, 0, 0]]), simulate="off"))
    assert off.proposals[0].physics is None and "physics" not in off.timings


def test_a_checked_answer_puts_the_held_proposals_first() -> None:
    from manifoundation.core.network import ContactPredictor

    predictor = ContactPredictor.from_checkpoint(str(WEIGHTS))
    out = run_pipeline(_inp(method="network", num_proposals=3, simulate="check"), predictor=predictor)
    assert len(out.proposals) == 3 and all(p.physics is not None for p in out.proposals)
    held = [p.physics is not None and p.physics.success and p.quality.success for p in out.proposals]
    assert held == sorted(held, reverse=True)


def test_a_requests_simulate_maps_unset_true_false_to_check_search_off() -> None:
    assert [physics_mode(v) for v in (None, True, False)] == ["check", "search", "off"]
