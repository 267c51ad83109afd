"""A cover of each fingertip body's surface samples by a few representatives, to bound the others' distances.

The contact model (`models.refine.contact`) needs the object's signed distance Φ of a fingertip body's samples
only where it decides something: the pad samples nearest the object (the contact and its ties) and the body's
samples nearest the object (the guard rows). Φ changes by at most the distance moved (a distance is 1-Lipschitz;
the point field's, to the nearest of the 8 nearest discs, by up to their radius h more), and a body is rigid, so
a sample ``s`` within δ of its representative ``r`` has ``Φ(r) − δ − h ≤ Φ(s) ≤ Φ(r) + δ + h`` at every pose:
measuring the representatives first bounds every sample, and only those whose lower bound can still be among the
nearest are measured.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

COVER_RADIUS = 6e-3
"""m: every sample lies within this of its representative (LEAP: 367 of its 2 578 samples are representatives;
smaller covers measure more representatives, larger ones more samples near the object: 4 and 8 mm measured more)."""


@dataclass(frozen=True)
class SampleCover:
    """``rep`` (K,): the index of each contact-surface sample's representative (a sample of the same body; a
    representative is its own), and ``delta`` (K,): the distance between them (m, body frame = world)."""

    rep: np.ndarray
    delta: np.ndarray

    @classmethod
    def build(cls, local: np.ndarray, body: np.ndarray, radius: float = COVER_RADIUS) -> SampleCover:
        """Greedy cover of the samples (K, 3) (body frame), body by body (K,): a sample farther than ``radius``
        from every representative so far becomes one; then each sample takes its nearest representative."""
        rep = np.zeros(len(local), dtype=np.int64)
        delta = np.zeros(len(local))
        for b in np.unique(body):
            idx = np.flatnonzero(body == b)
            pts = local[idx]
            chosen: list[int] = []
            far = np.full(len(idx), np.inf)
            for j in range(len(idx)):
                if far[j] > radius:
                    chosen.append(j)
                    far = np.minimum(far, np.linalg.norm(pts - pts[j], axis=1))
            d = np.linalg.norm(pts[:, None, :] - pts[chosen][None], axis=2)  # (k, c)
            near = np.argmin(d, axis=1)
            rep[idx] = idx[np.asarray(chosen)[near]]
            delta[idx] = d[np.arange(len(idx)), near]
        return cls(rep, delta)


def sample_cover(hand: Any) -> SampleCover:
    """The hand's `SampleCover` of ``hand.contact_surface`` (built once per hand)."""
    cache = hand.__dict__.setdefault("_sample_cover", {})
    if "cover" not in cache:
        surf = hand.contact_surface
        cache["cover"] = SampleCover.build(np.asarray(surf.local), np.asarray(surf.body))
    cover: SampleCover = cache["cover"]
    return cover
