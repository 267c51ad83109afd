"""How much of an object its labels call a valid contact, and what simple per-point rules score against them.

A heatmap network is trained towards the valid grasps of each example (`research.data.grasp_sets`): the grasps
sampled for the same object and hand that can produce its motion. Those are a *sample* of the grasps the hand
could make. Where the sample is sparse, the valid region (heat ≥ 0.5 of any valid grasp) covers a few per cent of
the points, scattered where the sampled palms happened to land, and the per-point probability that the best
possible network can learn — P(point in the region | geometry, motion) — is low everywhere it is not zero: a
flat map is then the right answer to the labels, not a failure to fit them. This report measures that:

- ``set_size``: valid grasps per example (mean), ``coverage``: the share of the points in the valid region,
  ``own``: the share in the example's own grasp's region;
- ``hit_random``, ``hit_push``, ``hit_far``: how often one point picked by a rule lies in the valid region — a
  random point (its expectation is ``coverage``), the point whose outward normal most opposes its motion (where a
  push would move it so), the point farthest from the bounding-box centre.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from research.data.grasp_sets import REGION_HEAT


@dataclass(frozen=True)
class LabelDensity:
    """The module docstring's figures over a set of examples."""

    examples: int
    set_size: float
    coverage: float
    own: float
    hit_random: float
    hit_push: float
    hit_far: float


def example_hits(
    points: np.ndarray, normals: np.ndarray, motion: np.ndarray, region: np.ndarray, rng: np.random.Generator
) -> tuple[bool, bool, bool]:
    """Whether a random point, the most-opposed-normal point and the farthest point lie in ``region``.

    Args:
        points, normals, motion: (N, 3) the object's points, outward normals and the task's per-point motion.
        region: (N,) bool valid region.
        rng: draws the random point.
    """
    unit = motion / np.maximum(np.linalg.norm(motion, axis=1, keepdims=True), 1e-12)
    push = int(np.argmin((normals * unit).sum(axis=1)))
    centre = 0.5 * (points.min(axis=0) + points.max(axis=0))
    far = int(np.argmax(np.linalg.norm(points - centre, axis=1)))
    return bool(region[rng.integers(len(points))]), bool(region[push]), bool(region[far])


def label_density(
    rows: list[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]], seed: int = 0
) -> LabelDensity:
    """The report over examples given as (points, normals, motion, set heat (G, N), own heat (N,)).

    Raises:
        ValueError: no examples.
    """
    if not rows:
        raise ValueError("no examples")
    rng = np.random.default_rng(seed)
    sizes, cover, own, hits = [], [], [], []
    for pts, nrm, mot, set_heat, own_heat in rows:
        region = np.asarray((np.asarray(set_heat) >= REGION_HEAT).any(axis=0), dtype=bool)
        sizes.append(len(set_heat))
        cover.append(float(region.mean()))
        own.append(float((own_heat >= REGION_HEAT).mean()))
        hits.append(example_hits(pts, nrm, mot, region, rng))
    h = np.asarray(hits, dtype=np.float64).mean(axis=0)
    return LabelDensity(len(rows), float(np.mean(sizes)), float(np.mean(cover)), float(np.mean(own)),
                        float(h[0]), float(h[1]), float(h[2]))  # fmt: skip
