"""Which epoch's checkpoint is the best: the lowest validation loss among the epochs measured on the same
validation examples. A run trained while its data is generated (``reload_each_epoch``) validates on a set that
grows with the data, and a loss on 37 examples does not compare with one on 256."""

from __future__ import annotations

import hashlib

import numpy as np

from research.training.sources import Source


def validation_fingerprint(sources: list[Source]) -> str:
    """Which validation examples an epoch is measured on: a digest of every source's validation labels (motions
    and heat); "" without any."""
    vals = [src.val for src in sources if src.val is not None]
    if not vals:
        return ""
    digest = hashlib.sha1()
    for val in vals:
        digest.update(np.ascontiguousarray(val.motion).tobytes())
        digest.update(np.ascontiguousarray(val.heat).tobytes())
    return digest.hexdigest()


def is_best(score: float, measured_on: str, best: float, best_on: str) -> bool:
    """Whether an epoch's validation loss ``score`` on the examples ``measured_on`` makes it the best checkpoint:
    lower than ``best`` on the same examples, or measured on other examples (losses on different examples do not
    compare: a run trained while its data was generated chose an epoch measured on 37 examples over the last one,
    measured on 256)."""
    return measured_on != best_on or score < best
