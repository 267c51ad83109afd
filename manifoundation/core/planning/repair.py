"""Repair of a waypoint in collision: the nearest collision-free position at the same orientation.

A planner (often an LLM) may put a waypoint where the object cannot be: inside a box, through a wall, below the
table. We keep the orientation it asked for and move the position the least: along each of the six axis
directions and ``DIRECTIONS`` more (a Fibonacci sphere, spread evenly, no randomness) we march out in steps of
``step`` until the pose is free, refine that distance by bisection to ``TOLERANCE``, and keep the shortest; then
a pattern search tilts the best direction by 8°, 4°, 2° and 1° (eight tilts each) while that shortens the move.
The answer is the nearest free position to within about a degree and 1 mm, plus ``CLEARANCE``, found within
``max_distance``; beyond it the waypoint is reported instead (`manifoundation.core.planning.types.InfeasibleWaypoint`).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from manifoundation.core.planning.poses import Pose

DIRECTIONS = 200
TOLERANCE = 1e-3
CLEARANCE = 2e-3
"""m added to the shortest free move, so that the repaired pose does not touch what it was moved out of."""


def fibonacci_directions(n: int) -> np.ndarray:
    """(n, 3) unit vectors spread evenly over the sphere (deterministic)."""
    i = np.arange(n) + 0.5
    z = 1.0 - 2.0 * i / n
    r = np.sqrt(1.0 - z * z)
    phi = np.pi * (1.0 + 5**0.5) * i
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=1)


def nearest_free(
    pose: Pose, is_free: Callable[[Pose], bool], max_distance: float, step: float = 0.005,
    directions: int = DIRECTIONS,
) -> Pose | None:  # fmt: skip
    """The collision-free pose nearest to ``pose`` by translation only (see module doc), or None.

    Args:
        pose: the requested pose (in collision).
        is_free: the collision test at a pose.
        max_distance: m, the farthest move allowed.
        step: m, the march's step along each direction.
        directions: how many directions are tried.
    """
    origin = np.asarray(pose.position, dtype=np.float64)

    def free_at(direction: np.ndarray, distance: float) -> bool:
        return is_free(Pose(origin + distance * direction, pose.quaternion))

    steps = np.arange(step, max_distance + 1e-12, step)

    def ray(d: np.ndarray, limit: float) -> float | None:
        """The free distance along d (to TOLERANCE), if shorter than ``limit``."""
        hit = next((s for s in steps if s < limit and free_at(d, s)), None)
        if hit is None:
            return None
        lo, hi = hit - step, hit  # lo in collision (or the start), hi free
        while hi - lo > TOLERANCE:
            mid = 0.5 * (lo + hi)
            lo, hi = (lo, mid) if free_at(d, mid) else (mid, hi)
        return hi if hi < limit else None

    best: tuple[float, np.ndarray] | None = None
    axes = np.vstack([np.eye(3), -np.eye(3)])
    for d in np.vstack([axes, fibonacci_directions(directions)]):
        found = ray(d, best[0] if best is not None else np.inf)
        if found is not None:
            best = (found, d)
    if best is None:
        return None
    for angle in np.radians([8.0, 4.0, 2.0, 1.0]):
        for d in _tilts(best[1], angle):
            found = ray(d, best[0] - 0.5 * TOLERANCE)
            if found is not None:
                best = (found, d)
    distance = best[0] + CLEARANCE if free_at(best[1], best[0] + CLEARANCE) else best[0]
    return Pose(origin + distance * best[1], np.asarray(pose.quaternion, dtype=np.float64).copy())


def _tilts(direction: np.ndarray, angle: float, count: int = 8) -> np.ndarray:
    """(count, 3) unit directions at ``angle`` (rad) from ``direction``, evenly around it."""
    helper = np.eye(3)[int(np.argmin(np.abs(direction)))]
    u = np.cross(direction, helper)
    u /= np.linalg.norm(u)
    v = np.cross(direction, u)
    phi = 2 * np.pi * np.arange(count) / count
    ring = np.cos(phi)[:, None] * u + np.sin(phi)[:, None] * v
    tilted: np.ndarray = np.cos(angle) * direction + np.sin(angle) * ring
    return tilted
