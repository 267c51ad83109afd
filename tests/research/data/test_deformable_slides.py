from pathlib import Path

import numpy as np
import pytest

from manifoundation.core.deformable.body import DeformableBody
from manifoundation.core.deformable.materials import RANGES, STIFF_ENDS, STIFF_RANGES
from manifoundation.core.deformable.metrics import shape_score
from manifoundation.core.deformable.rope import make_rope
from manifoundation.core.deformable.shapes import make_body
from manifoundation.core.deformable.simulate import simulate
from manifoundation.core.deformable.slides import slide_candidates
from research.data.deformable_examples import make_slide_example
from research.data.deformable_generate import (
    DeformableDataConfig,
    body_split,
    dataset_body,
    generate,
    load_body_file,
)


def _reaching(body: DeformableBody, d: np.ndarray, among: set[str] | None = None) -> set[str]:
    """Names of the candidate sets (those in ``among``; None: all) whose rollout reaches ``body`` slid by ``d``, one
    rollout each, judged here."""
    names = set()
    for m in slide_candidates(body, d):
        if among is not None and m.procedure not in among:
            continue
        out = simulate(body, m.contacts, m.motions)
        if out.stable and shape_score(body.material, body.points, body.points + d, out.cloud).success:
            names.add(m.procedure)
    return names


def test_a_slide_example_labels_exactly_the_candidate_sets_that_reach_the_slid_body() -> None:
    rope = make_rope(seed=5, properties={"friction": 0.6, "youngs_modulus": 1e5, "poisson_ratio": 0.3})
    ex = make_slide_example(rope, np.random.default_rng(2))
    assert ex is not None and ex.procedure == "slide"
    d = ex.motion[0]
    np.testing.assert_allclose(ex.motion, np.tile(d, (len(rope.points), 1)))  # every point asked to move by d
    names = _reaching(rope, d)
    reached = [m for m in slide_candidates(rope, d) if m.procedure in names]
    assert ex.label_sets == len(reached) >= 1
    for m in reached:
        assert np.all(ex.heat[m.contacts] == pytest.approx(1.0))
    missed = [m for m in slide_candidates(rope, d) if m.procedure not in names]
    labelled = {int(i) for m in reached for i in m.contacts}
    for m in missed:
        for i in m.contacts:
            if int(i) not in labelled:
                assert ex.heat[i] < 1.0


# 23 s: simulates every candidate set on two slides (a data-generation run): `make test-slow`
@pytest.mark.slow
def test_a_margin_keeps_the_sets_that_also_reach_a_longer_slide_which_drops_a_handkerchief_pushed_from_behind() -> None:
    handkerchief = make_body("cloth", "square", 100, {"friction": 0.6, "density": 600.0, "stretch": 1e3,
                                                      "bending": 1e-5})  # fmt: skip
    plain = make_slide_example(handkerchief, np.random.default_rng(2))
    kept = make_slide_example(handkerchief, np.random.default_rng(2), margin=0.4)
    assert plain is not None and kept is not None
    d = kept.motion[0]
    np.testing.assert_allclose(plain.motion[0], d)  # the same slide, a fifth of the size long
    assert 0.15 < np.linalg.norm(d) / handkerchief.size < 0.3
    short, long = _reaching(handkerchief, d), _reaching(handkerchief, d * 0.4 * handkerchief.size / np.linalg.norm(d))
    assert plain.label_sets == len(short) and kept.label_sets == len(short & long) and not kept.margin_fallback
    assert "slide_rear_one" in short and "slide_rear_one" not in long  # pushed from behind: only the short slide
    rear = slide_candidates(handkerchief, d)[3]
    assert rear.procedure == "slide_rear_one"
    # every set's shortfall is kept (≤ 1: reached), so other labels can be drawn without simulating again
    names = [m.procedure for m in slide_candidates(handkerchief, d)]
    assert kept.set_shortfall is not None and kept.set_shortfall_margin is not None
    assert {n for n, f in zip(names, kept.set_shortfall, strict=True) if f <= 1.0} == short
    assert {n for n, f in zip(names, kept.set_shortfall_margin, strict=True) if f <= 1.0} == short & long
    assert all(np.isnan(f) for n, f in zip(names, kept.set_shortfall_margin, strict=True) if n not in short)
    assert plain.heat[rear.contacts[0]] == pytest.approx(1.0) and kept.heat[rear.contacts[0]] < 1.0


def test_stiff_data_sets_reach_cards_and_sticks_and_old_manifests_keep_their_configuration() -> None:
    for option in ("slides", "stiff", "slide_margin", "stiff_ends", "paired_ends"):
        assert option not in DeformableDataConfig().to_dict()
    cfg = DeformableDataConfig(materials=("rope",), bodies=40, stiff=True)
    moduli = [dataset_body(cfg, "rope", i).properties["youngs_modulus"] for i in range(40)]
    lo, hi, _ = STIFF_RANGES["rope"]["youngs_modulus"]
    assert lo <= min(moduli) and max(moduli) <= hi
    assert max(moduli) > 1e2 * RANGES["rope"]["youngs_modulus"][1]  # beyond the default range: stick-like


def test_stiff_ends_draw_cards_and_handkerchiefs_often_and_leave_the_other_bodies_as_they_were() -> None:
    plain = DeformableDataConfig(materials=("cloth",), bodies=60, seed=3, stiff=True)
    ends = DeformableDataConfig(materials=("cloth",), bodies=60, seed=3, stiff=True, stiff_ends=0.5)
    soft, stiff = STIFF_ENDS["cloth"]

    def inside(box: dict[str, tuple[float, float, bool]], properties: dict[str, float]) -> bool:
        return all(lo <= properties[name] <= hi for name, (lo, hi, _) in box.items())

    near = {"plain": [0, 0], "ends": [0, 0]}
    kept = 0
    for i in range(60):
        before, after = dataset_body(plain, "cloth", i), dataset_body(ends, "cloth", i)
        assert np.array_equal(before.points, after.points)  # the same shape, only the properties may move
        for name, body in (("plain", before), ("ends", after)):
            near[name][0] += inside(soft, body.properties)
            near[name][1] += inside(stiff, body.properties)
        kept += before.properties == after.properties
        if before.properties != after.properties:  # moved into an end; the other properties stay
            assert inside(soft, after.properties) or inside(stiff, after.properties)
            assert after.properties["friction"] == before.properties["friction"]
    assert near["ends"][1] >= near["plain"][1] + 8 and near["ends"][0] >= near["plain"][0] + 4
    assert 15 <= kept <= 45  # about half the bodies keep their draw


def test_paired_ends_ask_one_shape_the_same_slide_as_a_soft_and_a_stiff_body(tmp_path: Path) -> None:
    cfg = DeformableDataConfig(materials=("rope",), bodies=2, examples_per_body=1, seed=4, slides=1.0, stiff=True,
                               paired_ends=True, test_fraction=0.0)  # fmt: skip
    soft, stiff = dataset_body(cfg, "rope", 0), dataset_body(cfg, "rope", 1)
    assert np.array_equal(soft.points, stiff.points)
    halves = DeformableDataConfig(materials=("rope",), bodies=40, seed=4, stiff=True, paired_ends=True,
                                  test_fraction=0.5)  # fmt: skip
    splits = [body_split(halves, "rope", i) for i in range(40)]
    assert splits[0::2] == splits[1::2] and len(set(splits)) == 2  # a shape is trained on or tested, never both
    (_, soft_top, _), (stiff_bottom, _, _) = (end["youngs_modulus"] for end in STIFF_ENDS["rope"])
    assert soft.properties["youngs_modulus"] <= soft_top and stiff.properties["youngs_modulus"] >= stiff_bottom
    assert soft.properties["friction"] == stiff.properties["friction"]
    generate(cfg, tmp_path, progress=False)
    files = [load_body_file(tmp_path / "deformable" / f"rope-0000{i}.npz") for i in (0, 1)]
    assert all(int(f["num_examples"]) == 1 for f in files)
    np.testing.assert_array_equal(files[0]["motion"], files[1]["motion"])  # the same slide asked of both


def test_a_data_set_of_slides_holds_slide_examples(tmp_path: Path) -> None:
    cfg = DeformableDataConfig(materials=("rope",), bodies=1, examples_per_body=2, seed=1, slides=1.0, stiff=True,
                               test_fraction=0.0)  # a training body keeps every example  # fmt: skip
    manifest = generate(cfg, tmp_path, progress=False)
    assert manifest["config"]["slides"] == 1.0 and manifest["config"]["stiff"] is True
    body = load_body_file(tmp_path / "deformable" / "rope-00000.npz")
    counts = manifest["bodies"]["rope-0"]["counts"]
    assert int(body["num_examples"]) + counts.get("slide_unreached", 0) == 2
    assert set(body.get("procedure", np.array(["slide"])).tolist()) <= {"slide"}
    shortfalls = body.get("slide_shortfall", np.zeros((0, 6)))
    assert shortfalls.shape == (int(body["num_examples"]), 6)
    assert np.all(np.nanmin(shortfalls, axis=1) <= 1.0)  # a kept slide is reached by some set
