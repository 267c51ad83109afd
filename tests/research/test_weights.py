"""`research.commands.weights.load_weights`: ``DIR`` and ``DIR@S`` (the same weights at another prior scale)."""

from __future__ import annotations

import pytest

from research.commands.weights import load_weights


def test_a_scale_after_the_directory_sets_the_prior_scale_and_a_bad_one_is_refused() -> None:
    plain = load_weights("manifoundation/core/weights/cpu1k")
    assert load_weights("manifoundation/core/weights/cpu1k@0.5").prior_scale == 0.5 != plain.prior_scale
    for bad in ("wide", "inf", "-1"):
        with pytest.raises(SystemExit, match="the scale after @ must be a finite number"):
            load_weights(f"manifoundation/core/weights/cpu1k@{bad}")
