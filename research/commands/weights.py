"""`DIR` or `DIR@S`: the weights an evaluation command loads (`mani-lab eval network`, `deformable`, `labels`)."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from manifoundation.core.network import ContactPredictor


def load_weights(spec: str) -> ContactPredictor:
    """The predictor of ``DIR`` or ``DIR@S``: the checkpoint in DIR, its latent samples at prior scale S if given."""
    from manifoundation.core.network import ContactPredictor

    path, _, scale = spec.partition("@")
    value = None
    if scale:
        try:
            value = float(scale)
        except ValueError:
            value = float("nan")
        if not math.isfinite(value) or value < 0:
            raise SystemExit(f"--weights {spec}: the scale after @ must be a finite number ≥ 0")
    predictor = ContactPredictor.from_checkpoint(path)
    if value is not None:
        predictor.prior_scale = value
    return predictor
