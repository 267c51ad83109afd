"""Valid regions re-sampled independently of each test case, for `mani-lab eval labels` and `mani-lab eval network`.

A case's valid region from the data (`research.evaluation.testset`) holds the grasps of one sampling run: a few of
the many grasps that can produce the case's motion. Each further sampling of the object (other seeds, the data's
sampler and settings) adds the regions of its grasps that can produce the case's wrench
(`research.evaluation.label_agreement.independent_region`). Every region so found is valid, so their union is a
subset of the case's true valid region: a top point's hit rate on the union is a lower bound of its hit rate on
the true region, and it rises towards it as samplings are added (as does a random point's).
"""

from __future__ import annotations

from multiprocessing import get_context
from typing import TYPE_CHECKING, Any

import numpy as np
from tqdm import tqdm

if TYPE_CHECKING:
    from research.evaluation.label_agreement import Grasp
    from research.evaluation.testset import TestCase


def _resample(job: tuple[Any, str, int, int]) -> tuple[int, int, list[Grasp]]:
    import torch

    from manifoundation.core.robots import get_hand
    from research.evaluation.label_agreement import resample_grasps

    torch.set_num_threads(1)
    cfg, hand, index, seed = job
    return index, seed, resample_grasps(cfg, index, get_hand(hand), seed)


def resampled_regions(
    data: str, cases: list[TestCase], hand: str, resamples: int, first_seed: int, workers: int, progress: bool = True
) -> tuple[list[np.ndarray], list[list[int]]]:
    """Each case's valid regions: the data's, then one per re-sampling of its object.

    Args:
        data: the generated data directory the cases come from (its config rebuilds the objects).
        cases: rigid cases with a valid region. hand: the hand whose grasps are re-sampled.
        resamples: R samplings per object; sampling r uses the generator ``[first_seed + r, object]``.
        workers: processes that re-sample the objects (spawned; the caller's module must be import-safe).

    Returns:
        Per case, its regions (1 + R, N) bool, the data's first; and per case the R counts of grasps that can
        produce its wrench.
    """
    from research.data.examples import ObjectInfo
    from research.data.generate import make_dataset_object
    from research.evaluation.label_agreement import case_wrench, independent_region
    from research.evaluation.testset import data_config

    cfg = data_config(data)
    objects = sorted({c.object_index for c in cases})
    seeds = [first_seed + r for r in range(resamples)]
    jobs = [(cfg, hand, i, s) for i in objects for s in seeds]
    grasps: dict[tuple[int, int], list[Grasp]] = {}
    if jobs:
        with get_context("spawn").Pool(max(1, workers)) as pool:
            found = pool.imap_unordered(_resample, jobs)
            for index, seed, sampled in tqdm(found, total=len(jobs), desc="re-sampling", disable=not progress):
                grasps[(index, seed)] = sampled
    info = {i: ObjectInfo.from_object(make_dataset_object(cfg, i)) for i in objects}
    regions: list[np.ndarray] = []
    counts: list[list[int]] = []
    for case in cases:
        if case.valid_region is None:
            raise ValueError(f"case of object {case.object_id} has no valid region to add re-samplings to")
        o = info[case.object_index]
        wrench = case_wrench(case, o.centre, o.length)
        more = [independent_region(case.points, case.normals, grasps[(case.object_index, s)], case.friction, wrench,
                                   o.centre, o.length) for s in seeds]  # fmt: skip
        regions.append(np.stack([case.valid_region] + [r for r, _ in more]))
        counts.append([k for _, k in more])
    return regions, counts
