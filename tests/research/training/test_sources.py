"""Batches of several sources: every example once an epoch, one source a batch, the single-source order kept."""

from __future__ import annotations

import numpy as np

from research.data.dataset import Examples
from research.training.sources import concat_examples, epoch_batches, first_examples


def test_one_source_keeps_the_single_source_order() -> None:
    batches = epoch_batches([10], 4, np.random.default_rng(3))
    perm = np.random.default_rng(3).permutation(10)
    assert [s for s, _ in batches] == [0, 0]
    assert [list(i) for _, i in batches] == [list(perm[:4]), list(perm[4:8])]


def test_a_source_smaller_than_a_batch_still_trains_alone() -> None:
    (only,) = epoch_batches([3], 4, np.random.default_rng(0))
    assert only[0] == 0 and sorted(only[1]) == [0, 1, 2]


def test_several_sources_visit_each_example_once_in_whole_batches_of_one_source() -> None:
    sizes = [37, 21, 8]
    batches = epoch_batches(sizes, 4, np.random.default_rng(1))
    assert len(batches) == sum(n // 4 for n in sizes)
    for s, n in enumerate(sizes):
        seen = np.concatenate([i for src, i in batches if src == s])
        assert len(seen) == 4 * (n // 4) and len(np.unique(seen)) == len(seen) and seen.max() < n
    assert all(len(i) == 4 for _, i in batches)
    order = [s for s, _ in batches]
    assert order != sorted(order)  # the sources' batches are interleaved, not one source after the other


def _examples(objects: int, per_object: int, tag: str) -> Examples:
    n, e = 5, objects * per_object
    rng = np.random.default_rng(objects)
    return Examples(rng.normal(size=(objects, n, 3)), rng.normal(size=(objects, n, 3)),
                    np.repeat(np.arange(objects), per_object), np.full(e, "panda_gripper"), np.full(e, "train"),
                    np.full(e, 0.5), np.zeros((e, n, 3)), rng.random((e, n)), np.zeros((e, n, 3)),
                    np.ones((e, n), dtype=bool), {"material": np.full(e, tag)})  # fmt: skip


def test_concatenated_examples_keep_each_example_on_its_own_object() -> None:
    a, b = _examples(2, 3, "rope"), _examples(3, 2, "cloth")
    both = concat_examples([a, b])
    assert len(both) == len(a) + len(b) and len(both.points) == 5
    for i in range(len(both)):
        src, j = (a, i) if i < len(a) else (b, i - len(a))
        np.testing.assert_array_equal(both.points[both.obj_index[i]], src.points[src.obj_index[j]])
        np.testing.assert_array_equal(both.heat[i], src.heat[j])
    assert list(both.extra["material"]) == ["rope"] * 6 + ["cloth"] * 6
    assert len(first_examples(both, 4)) == 4 and first_examples(both, None) is both
