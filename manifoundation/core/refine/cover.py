"""A cover of each fingertip body's surface samples by a few representatives, to bound the others' distances.

The contact model (`manifoundation.core.refine.contact`) needs the object's signed distance Φ of a fingertip body's
samples only where it decides something: the pad samples nearest the object (the contact and its ties) and the body's
samples nearest the object (the guard rows). Φ changes by at most the distance moved (a distance is 1-Lipschitz; the
point field's, to the nearest of the 8 nearest discs, by up to their radius h more), and a body is rigid, so a sample
``s`` within δ of its representative ``r`` has ``Φ(r) − δ − h ≤ Φ(s) ≤ Φ(r) + δ + h`` at every pose: measuring the
representatives first bounds every sample, and only those whose lower bound can still be among the nearest are measured.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from manifoundation.core.geometry.sample_cover import SampleCover

SIGN_BAND = 2e-3
"""m: a representative this near the surface bounds its samples on either side (`deciding_samples`)."""
COVER_RADIUS = 6e-3
"""m: every sample lies within this of its representative (LEAP: 367 of its 2 578 samples are representatives;
smaller covers measure more representatives, larger ones more samples near the object: 4 and 8 mm measured more)."""


def deciding_samples(
    field: Any, world: np.ndarray, wanted: np.ndarray, near_body: np.ndarray, margin: float,
    all_pads: bool, surf: Any, cover: SampleCover, tie: float, rows: int,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:  # fmt: skip
    """The sorted indices (T,) of the ``wanted`` samples (K,) whose Φ can decide a contact or a guard row of
    `manifoundation.core.refine.contact`, with their Φ (T,) and ∇Φ (T, 3) (world positions (K, 3)).

    The representatives' Φ bounds every sample's within its ``delta`` and the field's resolution (below); a pad
    sample is kept while its lower bound is within ``tie`` of its pad's smallest upper bound (the contact and its
    ties), a near body's sample (``near_body`` (m,)) while its lower bound is below the ``margin`` and the
    ``rows``-th smallest upper bound of its body (the guard rows). ``all_pads``: every pad sample (a region's
    score is not Φ); ``surf``: the hand's contact surface."""
    idx = np.flatnonzero(wanted)
    reps = np.unique(cover.rep[idx])
    phi_r, grad_r, _ = field.signed_distance(world[reps])
    # |Φ(s) − Φ(r)| ≤ δ + h: Φ is the distance to the nearest of the 8 nearest discs (radius h), not to all of
    # them; within SIGN_BAND of the surface either side is allowed (the points' side is least sure there)
    slack = float(getattr(field, "resolution", 0.0))
    low_r = np.where(np.abs(phi_r) < SIGN_BAND, -np.abs(phi_r), phi_r)
    high_r = np.where(np.abs(phi_r) < SIGN_BAND, np.abs(phi_r), phi_r)
    low, high = np.zeros(len(wanted)), np.zeros(len(wanted))
    low[reps], high[reps] = low_r, high_r
    lower = low[cover.rep[idx]] - cover.delta[idx] - slack
    upper = high[cover.rep[idx]] + cover.delta[idx] + slack
    owner, pad = surf.fingertip[idx], surf.pad[idx]
    keep = pad.copy() if all_pads else np.zeros(len(idx), dtype=bool)
    for i in range(len(near_body)):
        mine = owner == i
        if not all_pads:
            on_pad = mine & pad
            keep |= on_pad & (lower <= upper[on_pad].min() + tie + 1e-12)
        if near_body[i]:
            cap, ub = margin, upper[mine]
            if len(ub) >= rows:
                cap = min(cap, float(np.partition(ub, rows - 1)[rows - 1]))
            keep |= mine & (lower <= cap + 1e-12)
    extra = np.setdiff1d(idx[keep], reps, assume_unique=True)
    phi_e, grad_e = (field.signed_distance(world[extra])[:2] if len(extra)
                     else (np.zeros(0), np.zeros((0, 3))))  # fmt: skip
    at = np.concatenate([reps, extra])
    order = np.argsort(at)
    inside = wanted[at[order]]  # a representative of a wanted sample may itself not be wanted (a non-pad one)
    return (at[order][inside], np.concatenate([phi_r, phi_e])[order][inside],
            np.concatenate([grad_r, grad_e])[order][inside])  # fmt: skip


def sample_cover(hand: Any) -> SampleCover:
    """The hand's `SampleCover` of ``hand.contact_surface`` (built once per hand)."""
    cache = hand.__dict__.setdefault("_sample_cover", {})
    if "cover" not in cache:
        surf = hand.contact_surface
        cache["cover"] = SampleCover.build(np.asarray(surf.local), np.asarray(surf.body), COVER_RADIUS)
    cover: SampleCover = cache["cover"]
    return cover
