"""Network-only checks: multimodality, region-mask compliance, physical-property sensitivity.

- Multimodality: K = 8 latent samples per case; contacts by NMS; two contact sets are the same mode when every
  contact of one has a contact of the other within ``MODE_RADIUS`` × object size (and they have equally many);
  we report the mean number of distinct sets per case.
- Mask compliance: fraction of selected contacts (all samples, cases with a partial mask) inside the mask.
- Flat heatmaps: fraction of samples whose selection is empty (the pipeline then falls back to random contacts).
- Top point: fraction of samples whose highest point lies in the case's valid region (any grasp that can produce
  the motion, `research.evaluation.testset`), on cases without a region mask (a partial mask is drawn around the
  label's contacts, so inside it almost any point is near one), beside the share of the points the valid region
  covers there (what a random point scores: the region is as large as the grasps sampled per object make it);
  inference: p50 of one batch-1, K = 1 prediction. One sampling run holds a few of the grasps that can produce a
  case's motion; with ``resampled`` regions (the data's and those of further samplings of the object, each valid)
  the top point is also judged on their union: a subset of the true valid region, so its hit rate there is a lower
  bound of the hit rate on the true region (the random point's share likewise).
- Property sensitivity: the same case with friction 0.2 and 1.0; mean |Δ heatmap| and the fraction of cases
  whose selected contact sets differ.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from research.evaluation.testset import TestCase

if TYPE_CHECKING:
    from manifoundation.core.robots.hand import Hand


MODE_RADIUS = 0.1


def _inputs(case: TestCase, hand: Hand, friction: float | None = None) -> Any:
    from manifoundation.core.network import NetworkInput

    return NetworkInput(
        points=case.points,
        normals=case.normals,
        motion=case.motion,
        mask=case.mask,
        properties={"friction": case.friction if friction is None else friction},
        hand_points=hand.surface_points,
        hand_normals=hand.surface_normals,
        hand_key=hand.name,
    )


def judges_top_point(case: TestCase) -> bool:
    """Whether ``case``'s top point is judged: it has a valid region and no region mask (a partial mask is drawn
    around the label's contacts, so inside it almost any point is near one)."""
    return case.valid_region is not None and bool(case.mask.all())


def _select(case: TestCase, heat: np.ndarray, force: np.ndarray, hand: Hand, mask: bool = True) -> np.ndarray:
    from manifoundation.core.network import select_contacts

    return select_contacts(case.points, heat, force, case.mask if mask else None, hand.num_fingertips).indices


def _same(a: np.ndarray, b: np.ndarray, pts: np.ndarray, radius: float) -> bool:
    if len(a) != len(b):
        return False
    if not len(a):
        return True
    d = np.linalg.norm(pts[a][:, None] - pts[b][None], axis=-1)
    return bool((d.min(axis=1) <= radius).all() and (d.min(axis=0) <= radius).all())


@dataclass
class PropertyReport:
    cases: int
    mean_modes: float  # distinct contact sets among K samples
    samples: int
    mask_cases: int
    mask_compliance: float  # fraction of contacts inside the mask (must be 1)
    empty_selections: float  # fraction of samples with no contact above threshold
    friction_heat_delta: float  # mean |heat(μ=0.2) − heat(μ=1.0)|
    friction_changes_contacts: float  # fraction of cases whose contact set changes
    top_in_region: float = 0.0  # unmasked cases: fraction of samples whose top point is in a valid contact region
    top_cases: int = 0  # unmasked cases with a valid region
    empty_unmasked: float = 0.0  # flat (empty selection) share of the samples of cases without a region mask
    region_share: float = 0.0  # unmasked cases: mean share of the points in the valid region (a random point's hit)
    inference_ms_p50: float = 0.0  # one prediction, batch 1, K = 1
    top_in_union: float = 0.0  # the same on the union of the case's resampled regions (a lower bound, see above)
    union_share: float = 0.0  # mean share of the points in that union (a random point's hit)
    union_sources: int = 0  # regions in each union (the data's + re-samplings); 0: not measured


def evaluate_properties(
    cases: list[TestCase],
    hand: Hand,
    predictor: Any,
    k: int = 8,
    seed: int = 0,
    resampled: dict[int, np.ndarray] | None = None,
) -> PropertyReport:
    """The checks of the module docstring on ``cases`` with ``hand``.

    Args:
        resampled: case position in ``cases`` → its valid regions (S, N) bool (`research.commands.resampled_regions`),
        for the
            unmasked cases with a valid region; their union judges the top point once more.
    """
    modes, inside, total, empty, mask_cases = [], 0, 0, 0, 0
    deltas, changed, tops, top_total, times, empty_full, full_cases = [], 0, 0, 0, [], 0, 0
    shares: list[float] = []
    union_hits: list[float] = []
    union_shares: list[float] = []
    sources = 0
    for i, case in enumerate(cases):
        out = predictor.predict([_inputs(case, hand)], num_samples=k, seed=seed + i)[0]
        t0 = time.perf_counter()
        predictor.predict([_inputs(case, hand)], num_samples=1, seed=seed + i)
        times.append(time.perf_counter() - t0)
        if judges_top_point(case):
            assert case.valid_region is not None
            top = out.heatmaps.argmax(axis=1)
            tops += int(case.valid_region[top].sum())
            top_total += k
            shares.append(float(case.valid_region.mean()))
            if resampled is not None:
                union = np.asarray(resampled[i].any(axis=0))
                union_hits.append(float(union[top].mean()))
                union_shares.append(float(union.mean()))
                sources = len(resampled[i])
        scale = float(np.ptp(case.points, axis=0).max())
        sets = [_select(case, out.heatmaps[j], out.force_maps[j], hand) for j in range(k)]
        empty += sum(len(s) == 0 for s in sets)
        if case.mask.all():
            empty_full += sum(len(s) == 0 for s in sets)
            full_cases += 1
        distinct: list[np.ndarray] = []
        for s in sets:
            if len(s) and not any(_same(s, t, case.points, MODE_RADIUS * scale) for t in distinct):
                distinct.append(s)
        modes.append(len(distinct))
        if not case.mask.all():
            mask_cases += 1
            for s in sets:
                inside += int(case.mask[s].sum())
                total += len(s)
        lo, hi = predictor.predict([_inputs(case, hand, 0.2), _inputs(case, hand, 1.0)], num_samples=1, seed=seed + i)
        deltas.append(float(np.abs(lo.heatmaps[0] - hi.heatmaps[0]).mean()))
        a = _select(case, lo.heatmaps[0], lo.force_maps[0], hand)
        b = _select(case, hi.heatmaps[0], hi.force_maps[0], hand)
        changed += int(not _same(a, b, case.points, MODE_RADIUS * scale))
    n = max(len(cases), 1)
    return PropertyReport(
        cases=len(cases),
        mean_modes=float(np.mean(modes)) if modes else 0.0,
        samples=k,
        mask_cases=mask_cases,
        mask_compliance=inside / total if total else 1.0,
        empty_selections=empty / max(len(cases) * k, 1),
        friction_heat_delta=float(np.mean(deltas)) if deltas else 0.0,
        friction_changes_contacts=changed / n,
        top_in_region=tops / top_total if top_total else 0.0,
        top_cases=top_total // k,
        empty_unmasked=empty_full / max(full_cases * k, 1),
        region_share=float(np.mean(shares)) if shares else 0.0,
        inference_ms_p50=1e3 * float(np.median(times)) if times else 0.0,
        top_in_union=float(np.mean(union_hits)) if union_hits else 0.0,
        union_share=float(np.mean(union_shares)) if union_shares else 0.0,
        union_sources=sources,
    )
