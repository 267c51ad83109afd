"""Closing the fingers onto the object after refinement (issue 63: fingertips within 0.5 mm at the grasp).

The refinement converges with each pad within ``tip_tol`` (2 mm) of the guards' standoff (the larger of 0.5 mm and
the points' resolution, 0.45-1.3 mm on 2 048 points): its fingertips stop 1-3 mm off the object (median 1.1-2.8 mm
in the simulated grasp test), and while closing the first finger to arrive knocks the object away. `close_gaps`
continues the same refinement from a verified pose with a tight tip tolerance (``CLOSE_TIP_TOL``) and a smaller
standoff (`closing_standoff`): the pads are driven onto the surface while the wrench, the guards and the palm stay
in the model. The caller keeps the closed pose only if verification still accepts it
(`manifoundation.core.pipeline.run`); without a mesh verification measures penetration against the points' surface
grown by the resolution (≤ 0.5 mm), which bounds how far the standoff can shrink there.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace
from typing import TYPE_CHECKING, Any

import numpy as np

from manifoundation.core.refine.contact import ObjectField
from manifoundation.core.refine.refine import RefineConfig, RefineResult, refine
from manifoundation.core.refine.state import HandPose
from manifoundation.core.refine.wrench import WrenchTask

if TYPE_CHECKING:
    from manifoundation.core.robots.hand import Hand

CLOSE_TIP_TOL = 3e-4
"""m: the closing stage's tip tolerance (|Φ − standoff| of every pad)."""
CLOSE_ITERATIONS = 20
"""The closing stage's iteration budget (it starts at a verified pose: most end in < 15)."""
MIN_STANDOFF = 2.5e-4
"""m: the closing standoff never goes below this."""
POINTS_MARGIN = 4.5e-4
"""m: without a mesh the closing standoff is the resolution less this (verification allows 0.5 mm against the
points' surface grown by the resolution)."""


def closing_standoff(field: ObjectField) -> float:
    """The standoff (m) the closing stage brings the pads to: `MIN_STANDOFF` where the field has the object's mesh
    (``exact``: verification measures penetration on it, ≤ 1 mm); else the points' resolution less
    `POINTS_MARGIN`, at least `MIN_STANDOFF` (0.25-0.85 mm on 2 048 points of third-party objects, 1.07 mm on a
    6 cm box: where the points are sparse the true surface may lie up to the resolution beyond them, and
    verification's penetration test keeps that room)."""
    if getattr(field, "exact", None) is not None:
        return MIN_STANDOFF
    return max(MIN_STANDOFF, float(getattr(field, "resolution", 0.0)) - POINTS_MARGIN)


class ClosingField:
    """``field`` with its own ``standoff`` (`manifoundation.core.refine.contact.field_standoff`); everything else is
    the field's."""

    def __init__(self, field: ObjectField, standoff: float) -> None:
        self._field = field
        self.standoff = standoff

    def signed_distance(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        return self._field.signed_distance(x)

    def given_normal(self, x: np.ndarray) -> np.ndarray:
        return self._field.given_normal(x)

    @property
    def points(self) -> np.ndarray:
        return self._field.points

    def __getattr__(self, name: str) -> Any:
        return getattr(self._field, name)


def close_gaps(
    hand: Hand, field: ObjectField, task: WrenchTask, pose: HandPose, mu: float, config: RefineConfig,
    tip_field: Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]] | None = None, deadline: float | None = None,
    should_cancel: Callable[[], bool] | None = None,
) -> RefineResult:  # fmt: skip
    """The refinement continued from ``pose`` (verified) with `CLOSE_TIP_TOL` and `closing_standoff`."""
    closing = replace(config, tip_tol=CLOSE_TIP_TOL, verify_within=CLOSE_TIP_TOL, contact_tol=config.tip_tol,
                      max_iterations=min(CLOSE_ITERATIONS, config.max_iterations))  # fmt: skip
    near = ClosingField(field, closing_standoff(field))
    return refine(hand, near, task, pose, mu, closing, tip_field=tip_field, deadline=deadline,
                  should_cancel=should_cancel)  # fmt: skip
