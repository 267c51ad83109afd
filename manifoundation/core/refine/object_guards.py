"""The object-point guards of the contact model: object points near a fingertip measured against the convex parts
of its body, so that a sharp object edge cannot poke into a flat finger face between the finger's samples (1.8 mm
deep where the samples read 0.45 mm, LEAP on the example box). `manifoundation.core.refine.contact` adds their rows.
"""

from __future__ import annotations

from typing import Any, Protocol

import numpy as np

from manifoundation.core.refine.part_bounds import PartGrid, clearance, part_boxes, part_grids


class PointsField(Protocol):
    """What the guards use of the object: its points (an analytic field in tests has none: no guards)."""

    @property
    def points(self) -> np.ndarray:
        """(N, 3) the object's points."""
        ...


OBJECT_GUARDS_PER_FINGERTIP = 8
"""Object points nearest inside (or nearest to) each fingertip's convex parts that enter the rows ..."""
OBJECT_GUARD_MARGIN = 0.005
"""... if nearer than this (m)."""


def object_guards(
    field: PointsField, parts: list[tuple[np.ndarray, np.ndarray]], T: np.ndarray, centre: np.ndarray,
    radius: float, grids: list[PartGrid] | None = None, ball: np.ndarray | None = None,
    boxes: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:  # fmt: skip
    """Object points within ``radius`` of a fingertip body's ``centre`` against its convex parts (half-spaces
    (f, 4) ``n·x ≤ d`` and bounds, body frame; the body's pose ``T`` (4, 4)): each point's clearance to the part
    it is deepest in (max_f n_f·p − d_f: minus the depth inside, a lower bound on the distance outside), the world
    direction −n of the active face (moving the face's points that way increases it) and the point's foot on
    that face (world; a point fixed to the body whose Jacobian the rows use) — for the points nearest inside.
    ``ball``: the indices of the object points within ``radius`` of ``centre`` when the caller has them (sorted);
    ``boxes``: `part_boxes` of ``parts`` when the caller has them.

    With the parts' ``grids`` (`manifoundation.core.refine.part_bounds`), only the points whose clearance bounds let
    them be
    among the nearest are measured against every face: the same rows."""
    empty = np.zeros(0), np.zeros((0, 3)), np.zeros((0, 3))
    if not hasattr(field, "points") or not parts:  # an analytic field (tests): no object points to test
        return empty
    pts = np.asarray(field.points)[_ball(field, centre, radius) if ball is None else ball]
    if not len(pts):
        return empty
    R, t = T[:3, :3], T[:3, 3]
    local = (pts - t) @ R
    box = part_boxes(parts, OBJECT_GUARD_MARGIN) if boxes is None else boxes  # (2, P, 3): one test for all parts
    within = np.all((local[:, None, :] > box[0][None]) & (local[:, None, :] < box[1][None]), axis=2)  # (M, P)
    near_parts = [np.flatnonzero(column) for column in within.T]
    if grids is not None:
        pts, local, near_parts = _prune(local, pts, near_parts, grids)
    best = np.full(len(pts), np.inf)
    normal = np.zeros((len(pts), 3))
    for (planes, _), near in zip(parts, near_parts, strict=True):
        if not len(near):
            continue
        value, face = clearance(planes, local[near])
        better = value < best[near]
        best[near[better]] = value[better]
        normal[near[better]] = planes[face[better], :3]
    order = np.argsort(best)[:OBJECT_GUARDS_PER_FINGERTIP]
    order = order[best[order] < OBJECT_GUARD_MARGIN]
    n_world = normal[order] @ R.T
    foot = pts[order] - best[order, None] * n_world
    return best[order], -n_world, foot


def _prune(
    local: np.ndarray, pts: np.ndarray, near_parts: list[np.ndarray], grids: list[PartGrid]
) -> tuple[np.ndarray, np.ndarray, list[np.ndarray]]:
    """The points (and each part's near ones among them) whose clearance's lower bound is below the margin and
    the ``OBJECT_GUARDS_PER_FINGERTIP``-th smallest upper bound: the only ones that can be chosen."""
    lower, upper = np.full(len(pts), np.inf), np.full(len(pts), np.inf)
    for grid, near in zip(grids, near_parts, strict=True):
        if len(near):
            lo, hi = grid.bounds(local[near])
            np.minimum.at(lower, near, lo)
            np.minimum.at(upper, near, hi)
    cap = OBJECT_GUARD_MARGIN
    if len(upper) >= OBJECT_GUARDS_PER_FINGERTIP:
        cap = min(cap, float(np.partition(upper, OBJECT_GUARDS_PER_FINGERTIP - 1)[OBJECT_GUARDS_PER_FINGERTIP - 1]))
    keep = np.flatnonzero(lower <= cap + 1e-9)
    index = np.full(len(pts), -1)
    index[keep] = np.arange(len(keep))
    parts = [index[near][index[near] >= 0] for near in near_parts]
    return pts[keep], local[keep], parts


def part_grids_of(hand: Any) -> list[list[PartGrid]]:
    """Per fingertip, its parts' clearance grids (`manifoundation.core.refine.part_bounds`), built once per hand."""
    cache = hand.__dict__.setdefault("_part_grids", {})
    if "grids" not in cache:
        built: dict[bytes, list[PartGrid]] = {}  # fingers with the same mesh (LEAP's three) share their grids
        keys = [b"".join(planes.tobytes() + bounds.tobytes() for planes, bounds in parts)
                for parts in hand.fingertip_parts]  # fmt: skip
        for key, parts in zip(keys, hand.fingertip_parts, strict=True):
            if key not in built:
                built[key] = part_grids(parts, OBJECT_GUARD_MARGIN)
        cache["grids"] = [built[key] for key in keys]
    return list(cache["grids"])


def part_boxes_of(hand: Any) -> list[np.ndarray]:
    """Per fingertip, `part_boxes` of its parts grown by ``OBJECT_GUARD_MARGIN`` (cached on the hand)."""
    cache = hand.__dict__.setdefault("_part_grids", {})
    if "boxes" not in cache:
        cache["boxes"] = [part_boxes(parts, OBJECT_GUARD_MARGIN) for parts in hand.fingertip_parts]
    result: list[np.ndarray] = cache["boxes"]
    return result


def _ball(field: PointsField, centre: np.ndarray, radius: float) -> np.ndarray:
    return object_balls(field, centre[None], np.array([radius]))[0]


def object_balls(field: PointsField, centres: np.ndarray, radii: np.ndarray) -> list[np.ndarray]:
    """Per centre (k, 3), the sorted indices of the object points within its radius (k,): one tree query."""
    if not len(centres):
        return []
    if not hasattr(field, "points"):  # an analytic field (tests): no object points
        return [np.zeros(0, dtype=np.int64) for _ in centres]
    ball = getattr(field, "ball_indices", None)
    if ball is not None:
        return [np.asarray(b, dtype=np.int64) for b in ball(centres, radii)]
    pts = np.asarray(field.points)
    return [np.flatnonzero(np.linalg.norm(pts - c, axis=1) <= r) for c, r in zip(centres, radii, strict=True)]
