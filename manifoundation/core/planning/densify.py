"""Densification of a path: poses between its vertices so that no step exceeds the step sizes.

Each edge a → b is cut into n = max(1, ⌈|Δp| / translation_step⌉, ⌈angle / rotation_step⌉) equal steps along
the same straight line and shortest-arc slerp the planner checked (`Pose.interpolate`), so the dense poses lie
on validated motions.
"""

from __future__ import annotations

import itertools
import math

from manifoundation.core.planning.poses import Pose


def steps_between(a: Pose, b: Pose, translation_step: float, rotation_step: float) -> int:
    """How many equal steps the edge a → b needs (≥ 1)."""
    return max(
        1,
        math.ceil(a.translation_to(b) / translation_step - 1e-9),
        math.ceil(a.angle_to(b) / rotation_step - 1e-9),
    )


def densify(path: list[Pose], translation_step: float, rotation_step: float) -> list[Pose]:
    """The dense poses of ``path`` (its vertices kept, in order; no repeated vertex).

    Args:
        path: the vertices (≥ 1).
        translation_step: m, the largest translation of one step.
        rotation_step: rad, the largest rotation of one step.
    """
    out = [path[0]]
    for a, b in itertools.pairwise(path):
        if a.translation_to(b) < 1e-12 and a.angle_to(b) < 1e-12:
            continue
        n = steps_between(a, b, translation_step, rotation_step)
        out.extend(a.interpolate(b, k / n) for k in range(1, n))
        out.append(b)
    return out
