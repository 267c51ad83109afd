import numpy as np
import pytest

from manifoundation.core.deformable.metrics import shape_score
from manifoundation.core.deformable.procedures import Manipulation, rope_drag
from manifoundation.core.deformable.rope import make_rope
from manifoundation.core.deformable.simulate import simulate
from research.data.deformable_examples import labels, make_example, moving_alternative, union_labels


def test_union_labels_read_each_contacts_motion_back_even_where_sets_overlap() -> None:
    rope = make_rope(seed=0)
    first = Manipulation(np.array([3]), np.array([[0.1, 0.0, 0.0]]), "rope_drag")
    second = Manipulation(np.array([4, 20]), np.array([[0.0, 0.2, 0.0], [0.0, 0.0, 0.05]]), "moving_points")
    heat, motion_map = union_labels(rope, [first, second])
    for i, m in ((3, first.motions[0]), (4, second.motions[0]), (20, second.motions[1])):
        assert heat[i] == pytest.approx(1.0)
        np.testing.assert_allclose(motion_map[i] / heat[i], m, atol=1e-12)  # a sum of kernels would mix 3 and 4
    alone, _ = labels(rope, first)
    assert np.all(heat >= alone - 1e-12)


def test_a_verified_alternative_reaches_the_target_in_an_independent_rollout() -> None:
    rope = make_rope(seed=2)
    m = rope_drag(rope, np.random.default_rng(1))
    target = simulate(rope, m.contacts, m.motions).cloud
    alt = moving_alternative(rope, m, target)
    assert alt is not None  # a drag: the most-moved points with the target's displacement reproduce it
    again = simulate(rope, alt.contacts, alt.motions).cloud
    assert shape_score("rope", rope.points, target, again).success
    far = target + 0.5 * rope.size  # a target no rollout of these points reaches
    assert moving_alternative(rope, m, far) is None


def test_verified_examples_label_both_sets_and_unverified_ones_are_unchanged() -> None:
    rope = make_rope(seed=4)
    plain = make_example(rope, np.random.default_rng(0))
    verified = make_example(rope, np.random.default_rng(0), verify_moving=True)
    assert plain is not None and verified is not None
    np.testing.assert_array_equal(plain.motion, verified.motion)  # the same manipulation and target
    assert verified.moving_checked and not plain.moving_checked
    assert verified.label_sets == 2
    assert np.all(verified.heat >= plain.heat - 1e-9)
    moved = np.linalg.norm(verified.motion, axis=1)
    assert verified.heat[int(np.argmax(moved))] > 0.9  # the most-moved point is now a labelled contact
