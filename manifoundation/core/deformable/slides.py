"""Slides: the whole body moved across the table by one displacement d — the task of the paper's property figure.

The target is the body at rest translated by d (every point moves by d: the paper's "identical point clouds and
motions", asked of a handkerchief and a card, a rope and a stick). Which contacts reach it depends on the
material, and the simulator says which: pulled from its leading edge a handkerchief or a rope follows, pushed from
behind it bunches up; a card or a stick also goes when pushed from behind or at its middle.

`slide_candidates` names six contact sets by where they sit along d, each moved by d:

- ``front_pair``: the two points of the leading tenth of the cloud farthest apart across d (a cloth's front
  corners; a rope's leading stretch);
- ``front_one``: the most leading point near the middle across d;
- ``centre``: the point nearest the centroid;
- ``rear_one`` and ``rear_pair``: as the front ones, at the trailing edge;
- ``far_pair``: the two points of the cloud farthest apart (a rope's ends, a cloth's opposite corners), which the
  paper's figure drags on a rope.

`reaching_sets` simulates them and says which reach the slid body: the data's slide labels and the property
figure's named-set columns both read it.
"""

from __future__ import annotations

import numpy as np

from manifoundation.core.deformable.body import DeformableBody
from manifoundation.core.deformable.metrics import shortfall
from manifoundation.core.deformable.procedures import Manipulation
from manifoundation.core.deformable.simulate import simulate

SLIDE = (0.15, 0.4)  # |d| / the body's size
EDGE_FRACTION = 0.1  # the leading (trailing) tenth of the cloud holds the front (rear) pair
ACROSS_WEIGHT = 0.5  # the single front (rear) point: most leading, less half its distance across d
SET_NAMES = ("front_pair", "front_one", "centre", "rear_one", "rear_pair", "far_pair")  # `slide_candidates`' order
PUSH_SETS = ("slide_rear_one", "slide_rear_pair")  # contacts behind the body moved along d: they push it


def slide_displacement(body: DeformableBody, rng: np.random.Generator, fraction: float | None = None) -> np.ndarray:
    """A horizontal displacement (3,) m in a uniform heading, ``fraction`` × the body's size long (None: drawn
    in ``SLIDE``)."""
    angle = rng.uniform(0.0, 2.0 * np.pi)
    length = rng.uniform(*SLIDE) if fraction is None else fraction
    return np.array([np.cos(angle), np.sin(angle), 0.0]) * length * body.size


def along_and_across(points: np.ndarray, displacement: np.ndarray,
                     origin: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """Coordinates (N,), (N,) of ``points`` (N, 3) from ``origin`` (3,; None: their centroid) along the heading of
    ``displacement`` (3,) and across it (horizontal, to its left)."""
    heading = np.asarray(displacement, dtype=np.float64)[:2]
    heading = heading / max(float(np.linalg.norm(heading)), 1e-12)
    xy = np.asarray(points, dtype=np.float64)[:, :2]
    rel = xy - (xy.mean(axis=0) if origin is None else np.asarray(origin, dtype=np.float64)[:2])
    return rel @ heading, rel @ np.array([-heading[1], heading[0]])


def slide_candidates(body: DeformableBody, displacement: np.ndarray) -> list[Manipulation]:
    """The six named contact sets of the module doc, each contact moved by ``displacement`` (3,)."""
    points = body.points
    along, across = along_and_across(points, displacement)
    edge = max(2, round(EDGE_FRACTION * len(points)))
    sets: dict[str, list[int]] = {}
    for side, sign in (("front", 1.0), ("rear", -1.0)):
        rim = np.argsort(-sign * along)[:edge]
        sets[f"{side}_pair"] = sorted({int(rim[np.argmin(across[rim])]), int(rim[np.argmax(across[rim])])})
        sets[f"{side}_one"] = [int(np.argmax(sign * along - ACROSS_WEIGHT * np.abs(across)))]
    sets["centre"] = [int(np.argmin(along**2 + across**2))]
    gap = np.linalg.norm(points[:, None] - points[None], axis=-1)
    sets["far_pair"] = sorted(int(k) for k in np.unravel_index(np.argmax(gap), gap.shape))
    d = np.asarray(displacement, dtype=np.float64)
    return [Manipulation(np.array(sets[name], dtype=np.int64), np.tile(d, (len(sets[name]), 1)), f"slide_{name}")
            for name in SET_NAMES]  # fmt: skip


def reaching_sets(body: DeformableBody, displacement: np.ndarray,
                  names: set[str] | None = None) -> tuple[list[Manipulation], np.ndarray, float]:  # fmt: skip
    """The `slide_candidates` (those named in ``names``; None: all) whose rollouts reach ``body`` slid by
    ``displacement`` (3,) by the paper's metric; every set's shortfall (`SET_NAMES` order,
    `manifoundation.core.deformable.metrics.shortfall`: ≤ 1 reaches, inf unstable, NaN not simulated); the rollouts'
    seconds."""
    target = body.points + displacement
    valid, seconds = [], 0.0
    shortfalls = np.full(len(SET_NAMES), np.nan)
    for k, m in enumerate(slide_candidates(body, displacement)):
        if names is not None and m.procedure not in names:
            continue
        out = simulate(body, m.contacts, m.motions)
        seconds += out.seconds
        if not out.stable:
            shortfalls[k] = np.inf
            continue
        score = out.score(body, target)  # `Rollout.reaches`, scored once for the shortfall too
        shortfalls[k] = shortfall(body.material, score)
        if score.success:
            valid.append(m)
    return valid, shortfalls, seconds
