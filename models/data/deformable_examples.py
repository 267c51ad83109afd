"""One labelled deformable example: a manipulation simulated from rest, with what the network takes and its labels.

Stored per example (N the body's cloud): ``motion`` (N, 3) target per-point motion (rollout − start: what the
network is conditioned on), ``heat`` (N,) ground-truth contact heatmap and ``motion_map`` (N, 3) post-contact
motion map, both by the rigid data's documented kernel (`models.data.labels.heat_and_force`, the contact motions
in place of forces), ``mask`` (N,) region mask (all ones, or the contacts' neighbourhood, half each), the
contacts (cloud indices) and their motions, the procedure's name, and the motion split.

Motion split: a manipulation is an "unseen motion" when the heading of its mean contact motion lies within
``HELD_OUT_HALF_WIDTH`` of one of ``HELD_OUT_HEADINGS`` (four diagonals; ≈ 22 % of headings); those never enter
training (``test_so`` on training bodies, ``test_uo`` on test bodies).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from models.data.labels import heat_and_force, region_mask
from models.deformable.body import DeformableBody
from models.deformable.procedures import Manipulation, random_manipulation
from models.deformable.simulate import simulate

HELD_OUT_HEADINGS = np.deg2rad([45.0, 135.0, 225.0, 315.0])
HELD_OUT_HALF_WIDTH = np.deg2rad(10.0)


@dataclass
class DeformableExample:
    """See the module doc; arrays on the body's N cloud points, H contacts."""

    motion: np.ndarray
    heat: np.ndarray
    motion_map: np.ndarray
    mask: np.ndarray
    contacts: np.ndarray
    contact_motions: np.ndarray
    procedure: str
    unseen_motion: bool
    seconds: float


def is_unseen_motion(motions: np.ndarray) -> bool:
    """Whether the mean contact motion's heading is in the held-out set."""
    mean = np.asarray(motions, dtype=np.float64).reshape(-1, 3).mean(axis=0)
    heading = np.arctan2(mean[1], mean[0])
    gap = np.abs((heading - HELD_OUT_HEADINGS + np.pi) % (2 * np.pi) - np.pi)
    return bool(gap.min() <= HELD_OUT_HALF_WIDTH)


def labels(body: DeformableBody, manipulation: Manipulation) -> tuple[np.ndarray, np.ndarray]:
    """Ground-truth heatmap (N,) and post-contact motion map (N, 3) of a manipulation."""
    i = manipulation.contacts
    return heat_and_force(body.points, body.normals, body.points[i], body.normals[i], manipulation.motions,
                          body.size)  # fmt: skip


def make_example(body: DeformableBody, rng: np.random.Generator, tries: int = 3) -> DeformableExample | None:
    """A random manipulation of ``body`` simulated and labelled, or None when every try was unstable."""
    for _ in range(tries):
        m = random_manipulation(body, rng)
        out = simulate(body, m.contacts, m.motions)
        if not out.stable:
            continue
        heat, motion_map = labels(body, m)
        mask = region_mask(body.points, body.points[m.contacts], body.size, rng)
        return DeformableExample(out.cloud - body.points, heat, motion_map, mask, m.contacts, m.motions,
                                 m.procedure, is_unseen_motion(m.motions), out.seconds)  # fmt: skip
    return None
