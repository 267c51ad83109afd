"""One labelled deformable example: a manipulation simulated from rest, with what the network takes and its labels.

Stored per example (N the body's cloud): ``motion`` (N, 3) target per-point motion (rollout − start: what the
network is conditioned on), ``heat`` (N,) ground-truth contact heatmap and ``motion_map`` (N, 3) post-contact
motion map, both by the rigid data's documented kernel (`research.data.labels.heat_and_force`, the contact motions
in place of forces), ``mask`` (N,) region mask (all ones, or the contacts' neighbourhood, half each), the
contacts (cloud indices) and their motions, the procedure's name, and the motion split.

Verified labels (``verify_moving``, cloth and rope): one procedure's contacts are one valid answer among many
(a drag can take the cloth anywhere), so regressing them alone averages into a flat map. After the procedure's
rollout has given the target, the ``H`` points the target moves most, spread apart
(`manifoundation.core.deformable.answer.
moving_indices`, ``H`` the procedure's contact count, at least two), are moved by the target's displacement there
in the same simulator; when that rollout reaches the target by the paper's metric they are a second valid contact
set, and the labels are the union of both sets (:func:`union_labels`). Plasticine is never verified this way: its
target is the press after spring-back, which the target's displacement does not reach (docs/deformables.md).

Slides (cloth and rope, `manifoundation.core.deformable.slides`): the target is the body translated by one displacement;
the six named contact sets of `manifoundation.core.deformable.slides.slide_candidates` are simulated, and those that
reach the target by the paper's metric are the labels (their union); an example none of them reaches is dropped. What
reaches a slide depends on the properties (a handkerchief must be pulled from its front, a card can be pushed): what the
property figure asks the network to have learnt. With a margin (``slide_margin``), the labels keep only the sets that
also reach the same heading's slide at the margin's length: at a sixth of its size a handkerchief still follows a push
from behind, at a quarter it bunches up, and an open-loop answer should not sit on that edge. Each slide also keeps
every named set's `metrics.shortfall` at the slide and at the margin's length (``set_shortfall``,
``set_shortfall_margin``; stored as ``slide_shortfall``, NaN rows for other examples), so that other labels — the best
set alone, a weight by margin — can be drawn from a data set without simulating again.

Motion split: a manipulation is an "unseen motion" when the heading of its mean contact motion lies within
``HELD_OUT_HALF_WIDTH`` of one of ``HELD_OUT_HEADINGS`` (four diagonals; ≈ 22 % of headings); those never enter
training (``test_so`` on training bodies, ``test_uo`` on test bodies).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from manifoundation.core.deformable.answer import moving_indices
from manifoundation.core.deformable.body import DeformableBody
from manifoundation.core.deformable.procedures import Manipulation, random_manipulation
from manifoundation.core.deformable.simulate import simulate
from manifoundation.core.deformable.slides import SET_NAMES, reaching_sets, slide_displacement
from research.data.labels import heat_and_force, kernel, region_mask

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
    label_sets: int = 1
    moving_checked: bool = False
    margin_fallback: bool = False  # a slide whose labels no set reached with the margin (`make_slide_example`)
    # slides: each named set's `metrics.shortfall` (`slides.SET_NAMES` order; ≤ 1 reaches, inf unstable, NaN not
    # simulated) at the slide and at the margin's length, so that other labels can be drawn without simulating again
    set_shortfall: np.ndarray | None = None
    set_shortfall_margin: np.ndarray | None = None


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


def union_labels(body: DeformableBody, sets: list[Manipulation]) -> tuple[np.ndarray, np.ndarray]:
    """Heatmap (N,) and motion map (N, 3) of several valid contact sets: the kernel of every contact of every set,
    heat_j = max_i k_ij and motion_j = heat_j · m_i* (i* the contact of the largest kernel), so that motion / heat
    reads one contact's motion back (the quotient `manifoundation.core.network.loss.readout_loss` trains) even where two
    sets'
    contacts overlap."""
    idx = np.concatenate([s.contacts for s in sets])
    motions = np.concatenate([s.motions for s in sets])
    k = kernel(body.points, body.normals, body.points[idx], body.normals[idx], body.size)
    heat = k.max(axis=1)
    return heat, heat[:, None] * motions[np.argmax(k, axis=1)]


def moving_alternative(body: DeformableBody, manipulation: Manipulation, target: np.ndarray) -> Manipulation | None:
    """The target's most-moved points moved by its displacement, when their rollout reaches ``target`` (N, 3)."""
    motion = target - body.points
    count = max(2, len(manipulation.contacts))
    idx = moving_indices(body.points, np.arange(len(body.points)), motion, count)
    out = simulate(body, idx, motion[idx])
    if not out.reaches(body, target):
        return None
    return Manipulation(idx, motion[idx], "moving_points")


def make_example(body: DeformableBody, rng: np.random.Generator, tries: int = 3,
                 verify_moving: bool = False) -> DeformableExample | None:  # fmt: skip
    """A random manipulation of ``body`` simulated and labelled, or None when every try was unstable.

    Args:
        body: the body at rest. rng: draws the manipulation and the mask. tries: unstable rollouts allowed.
        verify_moving: cloth and rope: add the most-moved points to the labels when their rollout reaches the
            target (see the module doc; one more rollout).
    """
    for _ in range(tries):
        m = random_manipulation(body, rng)
        out = simulate(body, m.contacts, m.motions)
        if not out.stable:
            continue
        sets = [m]
        checked = verify_moving and body.material in ("cloth", "rope")
        if checked:
            alternative = moving_alternative(body, m, out.cloud)
            if alternative is not None:
                sets.append(alternative)
        heat, motion_map = labels(body, m) if len(sets) == 1 else union_labels(body, sets)
        every = np.unique(np.concatenate([s.contacts for s in sets]))
        mask = region_mask(body.points, body.points[every], body.size, rng)
        return DeformableExample(out.cloud - body.points, heat, motion_map, mask, m.contacts, m.motions,
                                 m.procedure, is_unseen_motion(m.motions), out.seconds, len(sets),
                                 checked)  # fmt: skip
    return None


def make_slide_example(body: DeformableBody, rng: np.random.Generator, margin: float = 0.0) -> DeformableExample | None:
    """A slide of ``body`` (cloth or rope) labelled by the candidate sets that reach it, or None when none does.

    Args:
        body: the body at rest. rng: draws the slide and the mask.
        margin: 0, or a slide length (fraction of the body's size): the labels keep only the sets that also reach
            the same heading's slide of at least this length — an open-loop answer with room to spare — unless
            none does (``margin_fallback``).

    The example's ``contacts`` are the first labelled set's (front to rear), ``label_sets`` how many were labelled.
    """
    displacement = slide_displacement(body, rng)
    valid, shortfall, seconds = reaching_sets(body, displacement)
    if not valid:
        return None
    fallback, shortfall_margin = False, np.full(len(SET_NAMES), np.nan)
    if margin > 0:
        kept, shortfall_margin, more = _holding(body, displacement, margin, valid)
        seconds += more
        fallback = not kept
        valid = valid if fallback else kept
    heat, motion_map = labels(body, valid[0]) if len(valid) == 1 else union_labels(body, valid)
    every = np.unique(np.concatenate([s.contacts for s in valid]))
    mask = region_mask(body.points, body.points[every], body.size, rng)
    first = valid[0]
    return DeformableExample(np.tile(displacement, (len(body.points), 1)), heat, motion_map, mask, first.contacts,
                             first.motions, "slide", is_unseen_motion(first.motions), seconds, len(valid),
                             margin_fallback=fallback, set_shortfall=shortfall,
                             set_shortfall_margin=shortfall_margin)  # fmt: skip


def _holding(body: DeformableBody, displacement: np.ndarray, fraction: float,
             sets: list[Manipulation]) -> tuple[list[Manipulation], np.ndarray, float]:  # fmt: skip
    """Those of ``sets`` (in their order) that also reach the same heading's slide ``fraction`` × size long — all of
    them, without a rollout, when the slide is already as long; every named set's shortfall there (NaN: not
    simulated); the rollouts' seconds."""
    longer = displacement * fraction * body.size / float(np.linalg.norm(displacement))
    if np.linalg.norm(longer) <= np.linalg.norm(displacement) * (1 + 1e-9):
        return sets, np.full(len(SET_NAMES), np.nan), 0.0
    kept, shortfalls, seconds = reaching_sets(body, longer, {m.procedure for m in sets})
    names = {m.procedure for m in kept}
    return [m for m in sets if m.procedure in names], shortfalls, seconds

