"""The paper's property figure as a check: one shape as both members of a pair (handkerchief / card, rope / stick).

Each shape gets one random manipulation, and each member's rollout under it is that member's target. A network
answers each target twice — with the member's own properties and with the other member's — and both answers are
simulated on the member: a network that reads the properties' meaning makes the own-property answer the better
one, a property-blind one ties, one whose answers merely change wins about half.

The paper's figure itself (`property_figure`): one shape as both members slid by the same d, each member answered
with its own properties; `figure_per_sample` answers the same shapes with several latent samples and counts each
answer's side of the centre and success.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from dataclasses import dataclass

import numpy as np

from manifoundation.core.deformable.body import DeformableBody
from manifoundation.core.deformable.procedures import Manipulation, random_manipulation
from manifoundation.core.deformable.simulate import simulate
from research.evaluation.deformable import Answer, DeformableCase

# The paper's property-sensitivity pairs: the same shape with two property sets.
SENSITIVITY_PAIRS: dict[str, tuple[str, dict[str, float], str, dict[str, float]]] = {
    "cloth": ("handkerchief", {"friction": 0.6, "density": 600.0, "stretch": 1e3, "bending": 1e-5},
              "card", {"friction": 0.6, "density": 600.0, "stretch": 1e5, "bending": 1e-2}),
    "rope": ("rope", {"friction": 0.6, "youngs_modulus": 1e4, "poisson_ratio": 0.3},
             "stick", {"friction": 0.6, "youngs_modulus": 1e9, "poisson_ratio": 0.3}),
}  # fmt: skip


@dataclass
class SensitivityResult:
    """One shape as both members of a pair: their rollouts under the same manipulation, and the network's contacts.

    Attributes:
        rollout_gap: mean distance between the two rollouts (normalised 2 m cube).
        contacts_differ: the network's contact sets for the same target motion differ (some contact farther than
            ``CONTACT_GAP`` of the size from every contact of the other set), or None without a network.
        sources: the network's contact source for each member.
        matched_error: for each member, with its own rollout as the target: the shape error (top mean, metric
            units) of the network's answer made with that member's properties, simulated on that member.
        swapped_error: the same target and body, the answer made with the other member's properties. A network
            that reads the properties' meaning makes ``matched < swapped``; one that ignores them ties.
    """

    material: str
    rollout_gap: float
    contacts_differ: bool | None
    sources: tuple[str, str]
    matched_error: tuple[float, float] | None = None
    swapped_error: tuple[float, float] | None = None

    def matched_wins(self) -> tuple[int, int]:
        """(members whose matched answer is the better one, members where the two answers tie)."""
        if self.matched_error is None or self.swapped_error is None:
            return 0, 0
        pairs = list(zip(self.matched_error, self.swapped_error, strict=True))
        return sum(m < s - TIE for m, s in pairs), sum(abs(m - s) <= TIE for m, s in pairs)


CONTACT_GAP = 0.1
TIE = 1e-9  # shape errors this close are one answer simulated twice (the simulator is deterministic)


def pair_bodies(material: str, count: int, seed: int) -> list[tuple[DeformableBody, DeformableBody]]:
    """``count`` shapes of ``material`` (square cloths or ropes, seeds ``seed`` …), each as both members of its
    `SENSITIVITY_PAIRS`: the same mesh with the first member's and the second member's properties."""
    from manifoundation.core.deformable.shapes import make_body

    _, first, _, second = SENSITIVITY_PAIRS[material]
    kind = "square" if material == "cloth" else "rope"
    bodies = [make_body(material, kind, seed + k, first) for k in range(count)]
    return [(a, a.with_properties(second)) for a in bodies]


def _top_error(body: DeformableBody, target: np.ndarray, contacts: np.ndarray, motions: np.ndarray) -> float:
    """The shape error (top mean) of ``contacts`` moved by ``motions`` on ``body`` against ``target``."""
    return simulate(body, contacts, motions).score(body, target).top_mean_error


def property_sensitivity(material: str, count: int, seed: int, network: Answer | None) -> list[SensitivityResult]:
    """``count`` shapes of ``material`` (square cloths or ropes) as both members of its `SENSITIVITY_PAIRS`.

    Each shape gets one random manipulation; each member's rollout under it is that member's target. With a
    network, each member is answered twice for its target — once with its own properties, once with the
    other member's — and both answers are simulated on it (``matched_error``, ``swapped_error``).
    """
    from manifoundation.core.deformable.metrics import NORMALISED_SIDE

    rng = np.random.default_rng([seed, 7])
    out = []
    for a, b in pair_bodies(material, count, seed):
        manip = random_manipulation(a, rng)
        ra, rb = simulate(a, manip.contacts, manip.motions), simulate(b, manip.contacts, manip.motions)
        gap = float(np.linalg.norm(ra.cloud - rb.cloud, axis=1).mean()) * NORMALISED_SIDE / a.size
        if network is None:
            out.append(SensitivityResult(material, gap, None, ("", "")))
            continue
        target = ra.cloud  # the same target for both: the shape the first member reaches
        pa, ma, sa, _ = network(DeformableCase(material, "sensitivity", a, manip, target))
        pb, mb, sb, _ = network(DeformableCase(material, "sensitivity", b, manip, target))
        d = np.linalg.norm(pa[:, None] - pb[None], axis=-1)
        differ = bool(max(d.min(axis=1).max(), d.min(axis=0).max()) > CONTACT_GAP * a.size)
        qa, na, *_ = network(DeformableCase(material, "sensitivity", a, manip, rb.cloud))
        qb, nb, *_ = network(DeformableCase(material, "sensitivity", b, manip, rb.cloud))
        matched = (_top_error(a, ra.cloud, pa, ma), _top_error(b, rb.cloud, qb, nb))
        swapped = (_top_error(a, ra.cloud, pb, mb), _top_error(b, rb.cloud, qa, na))
        out.append(SensitivityResult(material, gap, differ, (sa, sb), matched, swapped))
    return out


FIGURE_SLIDE = 0.3  # the figure's slide, × the body's size: far enough that a pushed handkerchief bunches up


@dataclass
class FigureMember:
    """One member of a pair asked to slide by d (the paper's figure: the same cloud, the same motion).

    Attributes:
        name: handkerchief, card, rope or stick.
        own_reaches: the network's answer made with this member's properties reaches the slid body when
            simulated on this member.
        other_reaches: the answer made with the other member's properties, simulated on this member.
        along: the own answer's contacts' mean position along d from the centroid, × size (+ front, − rear).
        source: the own answer's contact source (network, motion_fallback, ...).
        candidates: each `slides.slide_candidates` set's name → whether it reaches the slid body on this member
            (what the physics allows).
    """

    name: str
    own_reaches: bool
    other_reaches: bool
    along: float
    source: str
    candidates: dict[str, bool]


def _reaches(body: DeformableBody, target: np.ndarray, contacts: np.ndarray, motions: np.ndarray) -> bool:
    return simulate(body, contacts, motions).reaches(body, target)


def _contacts_along(case: DeformableCase, contacts: np.ndarray) -> float:
    """The mean position of ``contacts`` (H, 3) along the case's slide d from its body's centroid, × size (+ ahead,
    − behind)."""
    from manifoundation.core.deformable.slides import along_and_across

    body = case.body
    along, _ = along_and_across(contacts, case.manipulation.motions[0], origin=body.points.mean(axis=0))
    return float(along.mean()) / body.size


def figure_cases(material: str, count: int, seed: int) -> Iterator[tuple[DeformableCase, DeformableCase]]:
    """The figure's ``count`` shapes of ``material``, each as both members' cases of `SENSITIVITY_PAIRS`: one
    slide d (``FIGURE_SLIDE`` × size, a random heading; the manipulation's one motion) and one target for both,
    the first member's cloud translated by d."""
    from manifoundation.core.deformable.slides import slide_displacement

    rng = np.random.default_rng([seed, 11])
    for a, b in pair_bodies(material, count, seed):
        d = slide_displacement(a, rng, FIGURE_SLIDE)
        slide = Manipulation(np.zeros(1, dtype=np.int64), d[None], "slide")
        target = a.points + d
        yield DeformableCase(material, "figure", a, slide, target), DeformableCase(material, "figure", b, slide, target)


def property_figure(material: str, count: int, seed: int, network: Answer) -> list[tuple[FigureMember, FigureMember]]:
    """The paper's property figure on ``count`` shapes of ``material`` (square cloths or ropes).

    Each shape, as both members of its `SENSITIVITY_PAIRS`, is asked to slide by the same d (``FIGURE_SLIDE`` ×
    size, a random heading): the target is the cloud translated by d, identical for both. The network answers
    each member with its own properties; each answer is simulated on its own member and on the other one, and
    the named candidate sets show what each member's physics allows.
    """
    from manifoundation.core.deformable.slides import SET_NAMES, reaching_sets

    first_name, _, second_name, _ = SENSITIVITY_PAIRS[material]
    out = []
    for cases in figure_cases(material, count, seed):
        answers = [network(case) for case in cases]
        members = []
        for i, (name, case) in enumerate(zip((first_name, second_name), cases, strict=True)):
            body, target, d = case.body, case.target, case.manipulation.motions[0]
            own, other = answers[i], answers[1 - i]
            reached = {m.procedure.removeprefix("slide_") for m in reaching_sets(body, d)[0]}
            members.append(FigureMember(
                name, _reaches(body, target, own.points, own.motions),
                _reaches(body, target, other.points, other.motions), _contacts_along(case, own.points), own.source,
                {n: n in reached for n in SET_NAMES}))  # fmt: skip
        out.append((members[0], members[1]))
    return out


@dataclass
class SampleTally:
    """One member's answers to the figure's shapes over several answer functions (latent samples).

    Attributes:
        name: handkerchief, card, rope or stick.
        answers: answers counted (shapes × answer functions), own peaks and fallbacks alike.
        reaches: of them, those whose rollout on this member reaches the slid body.
        ahead, ahead_reaching: answers whose contacts' mean lies at or ahead of the centroid along d; reaching.
        behind, behind_reaching: the same behind the centroid.
    """

    name: str
    answers: int = 0
    reaches: int = 0
    ahead: int = 0
    ahead_reaching: int = 0
    behind: int = 0
    behind_reaching: int = 0

    def add(self, along: float, reached: bool) -> None:
        """Count one answer with its contacts' mean ``along`` d (× size) and whether it ``reached``."""
        self.answers += 1
        self.reaches += reached
        if along >= 0:
            self.ahead, self.ahead_reaching = self.ahead + 1, self.ahead_reaching + reached
        else:
            self.behind, self.behind_reaching = self.behind + 1, self.behind_reaching + reached


def figure_per_sample(
    material: str, count: int, seed: int, answers: Sequence[Answer]
) -> tuple[SampleTally, SampleTally]:
    """The property figure's ``count`` shapes and slides of ``material`` (`figure_cases`) answered by each of
    ``answers`` — e.g. the service at several seeds, one latent sample each — for both members; every answer is
    simulated on its own member. One figure run sees one sample a shape; this says how the samples spread."""
    first_name, _, second_name, _ = SENSITIVITY_PAIRS[material]
    tallies = (SampleTally(first_name), SampleTally(second_name))
    for cases in figure_cases(material, count, seed):
        for tally, case in zip(tallies, cases, strict=True):
            for answer in answers:
                proposal = answer(case)
                reached = _reaches(case.body, case.target, proposal.points, proposal.motions)
                tally.add(_contacts_along(case, proposal.points), reached)
    return tallies
