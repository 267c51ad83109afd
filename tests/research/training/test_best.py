"""The best checkpoint's rule: losses compare only on the same validation examples."""

from __future__ import annotations

import numpy as np

from research.training.best import is_best, validation_fingerprint
from research.training.sources import RIGID, Source


def _source(motion: np.ndarray, heat: np.ndarray) -> Source:
    from research.data.dataset import Examples

    e = len(heat)
    val = Examples(
        points=np.zeros((1, heat.shape[1], 3)), normals=np.zeros((1, heat.shape[1], 3)),
        obj_index=np.zeros(e, dtype=np.int64), hand=np.array(["allegro"] * e), split=np.array(["test_so"] * e),
        friction=np.ones(e), motion=motion, heat=heat, force_map=np.zeros_like(motion),
        mask=np.ones(heat.shape, dtype=bool), extra={},
    )  # fmt: skip
    return Source(RIGID, ("d",), val, val)


def test_a_lower_loss_is_best_only_on_the_same_examples() -> None:
    assert is_best(0.3, "a", 0.4, "a")
    assert not is_best(0.5, "a", 0.4, "a")
    assert is_best(0.5, "b", 0.4, "a")  # measured on other examples: no comparison, the newer one
    assert is_best(1.0, "a", float("inf"), "")  # the first epoch


def test_the_fingerprint_changes_with_the_validation_examples_and_not_otherwise() -> None:
    rng = np.random.default_rng(0)
    motion, heat = rng.normal(size=(3, 8, 3)), rng.uniform(size=(3, 8))
    first = validation_fingerprint([_source(motion, heat)])
    assert first == validation_fingerprint([_source(motion.copy(), heat.copy())])
    assert first != validation_fingerprint([_source(motion[:2], heat[:2])])  # the set grew or shrank
    assert validation_fingerprint([]) == ""
