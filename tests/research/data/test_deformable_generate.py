import json
from pathlib import Path

import numpy as np
import pytest

from manifoundation.core.deformable.procedures import cloth_fold, plasticine_push
from manifoundation.core.deformable.rope import make_rope
from manifoundation.core.deformable.shapes import make_body
from research.data.deformable_examples import is_unseen_motion, labels, make_example
from research.data.deformable_generate import DeformableDataConfig, generate, load_body_file


def test_heat_peaks_at_the_contacts_and_the_motion_map_reads_their_motion() -> None:
    rope = make_rope(seed=0)
    from manifoundation.core.deformable.procedures import Manipulation

    m = Manipulation(np.array([3]), np.array([[0.1, 0.0, 0.0]]), "rope_drag")
    heat, motion_map = labels(rope, m)
    assert int(np.argmax(heat)) == 3 and heat[3] == pytest.approx(1.0)
    np.testing.assert_allclose(motion_map[3], [0.1, 0.0, 0.0], rtol=1e-9)


def test_fold_moves_keypoints_to_their_mirror_images() -> None:
    cloth = make_body("cloth", "square", seed=1)
    m = cloth_fold(cloth, np.random.default_rng(0))
    centre = cloth.points.mean(axis=0)
    for i, d in zip(m.contacts, m.motions, strict=True):
        p, q = cloth.points[i] - centre, cloth.points[i] + d - centre
        assert np.linalg.norm(p) == np.linalg.norm(q) or abs(np.linalg.norm(p) - np.linalg.norm(q)) < 1e-9


def test_push_is_one_or_two_fingertip_presses_of_upward_regions_into_the_body() -> None:
    counts = set()
    for kind, seed in (("sphere", 0), ("box", 1), ("composite", 2), ("blob", 3), ("ellipsoid", 4)):
        body = make_body("plasticine", kind, seed=seed)
        for k in range(4):
            m = plasticine_push(body, np.random.default_rng(k))
            counts.add(len(m.contacts))
            assert len(set(m.contacts.tolist())) == len(m.contacts) and m.motions.shape == (len(m.contacts), 3)
            inward = -np.einsum("ij,ij->i", body.normals[m.contacts], m.motions)
            assert np.all(inward > 0) and np.all(m.motions[:, 2] < 0)  # pressed down, into the body
            depth = np.linalg.norm(m.motions, axis=1) / body.size
            assert np.all((depth > 0.099) & (depth < 0.26))
    assert counts == {1, 2}


def test_unseen_headings() -> None:
    assert is_unseen_motion(np.array([[1.0, 1.0, 0.0]]))
    assert not is_unseen_motion(np.array([[1.0, 0.0, 0.0]]))


def test_example_motion_is_the_simulated_displacement() -> None:
    rope = make_rope(seed=4)
    ex = make_example(rope, np.random.default_rng(0))
    assert ex is not None
    assert ex.motion.shape == rope.points.shape
    moved = np.linalg.norm(ex.motion, axis=1)
    assert moved[ex.contacts].min() > 0.5 * np.linalg.norm(ex.contact_motions, axis=1).min()


def test_generation_is_resumable_and_seeded(tmp_path: Path) -> None:
    cfg = DeformableDataConfig(materials=("rope",), bodies=1, examples_per_body=1, seed=3)
    first = generate(cfg, tmp_path / "a", progress=False)
    again = generate(cfg, tmp_path / "a", progress=False)  # nothing left to do: same manifest
    assert again["bodies"] == first["bodies"]
    other = generate(cfg, tmp_path / "b", progress=False)
    a = load_body_file(tmp_path / "a" / "deformable" / "rope-00000.npz")
    b = load_body_file(tmp_path / "b" / "deformable" / "rope-00000.npz")
    np.testing.assert_array_equal(a["points"], b["points"])
    assert json.loads((tmp_path / "a" / "deformable" / "manifest.json").read_text())["totals"] == first["totals"]
    assert other["totals"]["examples"] == first["totals"]["examples"]
