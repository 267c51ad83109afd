"""The network's top point against valid regions sampled independently of the example that set the motion.

A test case's valid region (`research.evaluation.testset`) is the union of the contact regions of the grasps that
can produce its motion, taken from the same sampling run that produced the motion: the case's own grasp and its
near copies (other finger combinations from the same palms) are always among them. How much of the figure "top
point in a valid region" is that run, and how much the geometry? Here each case's object is sampled again with
other seeds — the data's sampler and settings (`research.data.sampling.sample_grasps`) — and the grasps of each
re-sampling that can produce the case's wrench (the same pyramid programme as `research.data.grasp_sets`) give a
region that owes nothing to the example. The report gives, per label source, the share of the points it marks (a
random point's hit) and how often the network's top point lies in it; the same for the union of every source
(denser labels); and two label oracles: how often a point of one source's region lies in another's, and how often
the point most of the other sources mark lies in the held-out one — what labels this sparse agree with
themselves, a ceiling for any predictor judged on one of them.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from manifoundation.core.refine.grasp import grasp_maps
from research.data.grasp_sets import MAX_SET, feasible_forces, set_region

if TYPE_CHECKING:
    from manifoundation.core.robots.hand import Hand
    from research.data.generate import DataConfig
    from research.evaluation.testset import TestCase

Grasp = tuple[np.ndarray, np.ndarray]
"""A sampled grasp's contacts (m, 3) and their outward normals (m, 3)."""


def resample_grasps(cfg: DataConfig, index: int, hand: Hand, seed: int) -> list[Grasp]:
    """Object ``index`` of the data set ``cfg`` sampled again for ``hand`` with the data's palms and grasp count,
    from the generator ``[seed, index]`` (the data's own runs use ``[cfg.seed, index, hand]``)."""
    from research.data.checks import ObjectField
    from research.data.generate import make_dataset_object
    from research.data.sampling import sample_grasps

    obj = make_dataset_object(cfg, index)
    rng = np.random.default_rng([seed, index])
    grasps = sample_grasps(hand, ObjectField(obj.mesh, seed=obj.seed), obj.size, rng, palms=cfg.palms,
                           max_grasps=cfg.grasps_per_job)  # fmt: skip
    return [(np.asarray(g.contacts), np.asarray(g.normals)) for g in grasps]


def case_wrench(case: TestCase, centre: np.ndarray, length: float) -> np.ndarray:
    """(6,) the scaled wrench of a rigid case's own grasp and forces (what its motion was made from)."""
    assert case.grasp_contacts is not None and case.grasp_forces is not None
    own = np.isfinite(case.grasp_contacts[0][:, 0])
    maps = grasp_maps(case.grasp_contacts[0][own], centre, length)
    wrench: np.ndarray = np.einsum("mij,mj->i", maps, case.grasp_forces[0][own])
    return wrench


def independent_region(points: np.ndarray, normals: np.ndarray, grasps: list[Grasp], friction: float,
                       wrench: np.ndarray, centre: np.ndarray, length: float) -> tuple[np.ndarray, int]:  # fmt: skip
    """The valid region (N,) bool of ``grasps`` for a rigid ``wrench`` (6,) on the object's points (N, 3) and
    normals: the points where any grasp that can produce it (forces in the friction pyramids, normal forces ≤ 1;
    at most ``MAX_SET``, in order) has heat ≥ ``REGION_HEAT``; and how many grasps can."""
    chosen: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []
    for contacts, contact_normals in grasps:
        forces = feasible_forces(contacts, contact_normals, friction, np.eye(6), wrench, centre, length)
        if forces is not None:
            chosen.append((contacts, contact_normals, forces))
        if len(chosen) == MAX_SET:
            break
    if not chosen:
        return np.zeros(len(points), dtype=bool), 0
    contacts, contact_normals, forces = zip(*chosen, strict=True)
    return set_region(points, normals, contacts, contact_normals, forces), len(chosen)


@dataclass(frozen=True)
class LabelAgreement:
    """The module docstring's figures over cases; label sources: the data's, then each re-sampling.

    Attributes:
        cases: cases measured. sources: 1 + re-samplings.
        coverage: (S,) mean share of the points each source's region marks (a random point's hit).
        top_hit: (S,) share of the network's top points (every sample of every case) in each source's region.
        union_coverage, union_top_hit: the same for the union of every source's region.
        denser_coverage, denser_top_hit: (S,) the same for the union of the first 1, 2, ..., S sources.
        oracle_pair: how often a point of one source's region lies in another's (mean over ordered pairs).
        oracle_held_out: how often the point most of the other sources mark lies in the held-out one.
    """

    cases: int
    sources: int
    coverage: np.ndarray
    top_hit: np.ndarray
    union_coverage: float
    union_top_hit: float
    denser_coverage: np.ndarray
    denser_top_hit: np.ndarray
    oracle_pair: float
    oracle_held_out: float


def label_agreement(regions: list[np.ndarray], tops: list[np.ndarray]) -> LabelAgreement:
    """The figures of `LabelAgreement` from each case's regions (S, N) bool (the data's first) and its network's
    top points (K,) (indices of each sample's highest point)."""
    coverage, top_hit, union_cov, union_hit, pair, held = [], [], [], [], [], []
    denser_cov, denser_hit = [], []
    for region, top in zip(regions, tops, strict=True):
        coverage.append(region.mean(axis=1))
        top_hit.append(region[:, top].mean(axis=1))
        first = np.logical_or.accumulate(region, axis=0)  # (S, N): the union of the first k + 1 sources
        denser_cov.append(first.mean(axis=1))
        denser_hit.append(first[:, top].mean(axis=1))
        union = np.asarray(region.any(axis=0))
        union_cov.append(union.mean())
        union_hit.append(union[top].mean())
        for j in range(len(region)):
            for k in range(len(region)):
                if j != k and region[k].any():
                    pair.append(region[j, region[k]].mean())
            votes = np.delete(region, j, axis=0).sum(axis=0)
            if votes.max() > 0:  # ties: the expected hit of one of the most-marked points
                held.append(region[j, votes == votes.max()].mean())
    return LabelAgreement(
        cases=len(regions), sources=len(regions[0]) if regions else 0,
        coverage=np.mean(coverage, axis=0), top_hit=np.mean(top_hit, axis=0),
        union_coverage=float(np.mean(union_cov)), union_top_hit=float(np.mean(union_hit)),
        denser_coverage=np.mean(denser_cov, axis=0), denser_top_hit=np.mean(denser_hit, axis=0),
        oracle_pair=float(np.mean(pair)) if pair else float("nan"),
        oracle_held_out=float(np.mean(held)) if held else float("nan"),
    )  # fmt: skip
