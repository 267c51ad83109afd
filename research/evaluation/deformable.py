"""Deformable evaluation (paper Table I, deformable columns): apply an answer in the simulator, compare with the target.

Cases, per material and split, are drawn exactly as `research.data.deformable_generate` draws its bodies (same seed,
same ids, same train/test split by id): ``test_so`` takes training bodies, ``test_uo`` test bodies, and each case is
one of the material's procedures (`manifoundation.core.deformable.procedures`) redrawn until its motion is an unseen
one (`research.data.deformable_examples.is_unseen_motion`), simulated from rest to give the target cloud (a
plasticine press whose target the body left alone on its board already reaches is no task: that body is skipped, as
a body whose press is unstable is). Every method's contacts and motions are then simulated from the same rest state
with the same `simulate` and scored by `metrics.shape_score` (plasticine: issue 59's rule, the paper's all-points
rule beside it in ``paper_success``).

Methods (all in one run, on the same cases):

- ``random_motion``: H random cloud points (spread), each with a random motion (uniform direction, length
  uniform up to the target's largest displacement) — the paper's baseline.
- ``random_target_motion``: the same points, each with the target's displacement at it.
- ``moving_target_motion``: the points the target moves most, spread apart (`manifoundation.core.deformable.answer.
  moving_indices`, the service's fallback when the heatmap is flat), each with the target's displacement.
- ``moving_corrected``: the same points as ``moving_target_motion``, their motions corrected through the
  service's simulator (`manifoundation.core.pipeline.run_pipeline` with ``simulate_rollout`` and
  ``rollout_corrections``:
  closed loop on the body rebuilt from the cloud), then simulated on the case's own body like every method.
- ``ground_truth``: the procedure's own contacts and motions — the ceiling the simulator allows (the target was
  made by them, so it measures the simulator's repeatability: 100 % when deterministic).
- ``ground_truth_cut``: the procedure's contacts cut to the ``contacts`` the target moves most, with their own
  motions — the ceiling for an answer with that many contacts (a plasticine press moves a whole cluster).
- ``network``: `manifoundation.core.pipeline.run_pipeline` with method "network" (what the service answers: NMS contacts
on
  the heatmap, the motion map there; H ≤ the hand's fingertips), first proposal.
- ``network_samples``, ``network_checked``, ``random_checked``: the service asked for K proposals
  (`research.evaluation.deformable_service`): the network's per-sample success rate, and the first answer after the
  service's own rollout check, for the network and for random contacts at the same budget.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from manifoundation.core.deformable.body import DeformableBody
from manifoundation.core.deformable.materials import MATERIALS
from manifoundation.core.deformable.metrics import ShapeScore, paper_solid_success
from manifoundation.core.deformable.procedures import Manipulation, random_manipulation
from manifoundation.core.deformable.simulate import contact_vertices, simulate
from research.data.deformable_examples import is_unseen_motion
from research.data.deformable_generate import DeformableDataConfig, dataset_body
from research.evaluation.deformable_service import SERVICE_METHODS, Answers, Proposal, ask_service

if TYPE_CHECKING:
    from manifoundation.core.network.inference import ContactPredictor
    from manifoundation.core.robots import Hand

METHODS = ("random_motion", "random_target_motion", "moving_target_motion", "moving_corrected", "ground_truth",
           "ground_truth_cut", "network", *SERVICE_METHODS)  # fmt: skip
SPLITS = ("test_so", "test_uo")
MOTION_TRIES = 60


@dataclass
class DeformableCase:
    """One held-out case: a body at rest, the manipulation that made the target, and the target cloud (N, 3)."""

    material: str
    split: str
    body: DeformableBody
    manipulation: Manipulation
    target: np.ndarray


@dataclass
class MethodResult:
    """One method on one case."""

    method: str
    score: ShapeScore
    contacts: int
    source: str = ""
    readback: float = float("nan")  # network answers: median |the head's own motion| / |target displacement| there
    rate: float | None = None  # several answers judged (network_samples): the fraction that succeed

    @property
    def success(self) -> float:
        """1 or 0, or the fraction of the answers that succeed."""
        return float(self.score.success) if self.rate is None else self.rate


@dataclass
class DeformableReport:
    """All cases and their methods' results, with a summary per (material, split, method)."""

    cases: list[DeformableCase] = field(default_factory=list)
    results: list[list[MethodResult]] = field(default_factory=list)

    def success_rates(self, material: str, split: str) -> dict[str, float]:
        """Success % per method on the (material, split) cases."""
        idx = [i for i, c in enumerate(self.cases) if (c.material, c.split) == (material, split)]
        found = {r.method for i in idx for r in self.results[i]}
        return {m: 100.0 * float(np.mean([r.success for i in idx for r in self.results[i] if r.method == m]))
                for m in found}  # fmt: skip

    def summary(self) -> list[dict[str, object]]:
        rows: list[dict[str, object]] = []
        keys = sorted({(c.material, c.split) for c in self.cases}, key=lambda k: (MATERIALS.index(k[0]), k[1]))
        for material, split in keys:
            idx = [i for i, c in enumerate(self.cases) if (c.material, c.split) == (material, split)]
            for method in METHODS:
                rs = [r for i in idx for r in self.results[i] if r.method == method]
                if not rs:
                    continue
                rows.append({
                    "material": material, "split": split, "method": method, "cases": len(rs),
                    "success": 100.0 * float(np.mean([r.success for r in rs])),
                    "paper_success": 100.0 * float(np.mean([paper_solid_success(r.score) for r in rs])),
                    "closure": float(np.median([r.score.closure for r in rs])),
                    "mean_error": float(np.median([r.score.mean_error for r in rs])),
                    "top_mean_error": float(np.median([r.score.top_mean_error for r in rs])),
                    "network_contacts": sum(r.source == "network" for r in rs),
                    "network_successes": sum(r.source == "network" and r.score.success for r in rs),
                    "network_readback": _median_or_nan([r.readback for r in rs if r.source == "network"]),
                })  # fmt: skip
        return rows


def _median_or_nan(values: list[float]) -> float:
    return float(np.median(values)) if values else float("nan")


def build_cases(material: str, split: str, count: int, seed: int, data: DeformableDataConfig) -> list[DeformableCase]:
    """``count`` cases of ``material`` on the ``split``'s bodies (see the module doc)."""
    from research.data.generate import object_split

    cases: list[DeformableCase] = []
    want = "train" if split == "test_so" else "test"
    m_index = MATERIALS.index(material)
    for i in range(count * 20):
        if len(cases) == count:
            break
        body = dataset_body(data, material, i)
        if object_split(body.id, data.test_fraction) != want:
            continue
        rng = np.random.default_rng([seed, m_index, i, 2])
        for _ in range(MOTION_TRIES):
            manip = random_manipulation(body, rng)
            if is_unseen_motion(manip.motions):
                break
        else:
            continue
        out = simulate(body, manip.contacts, manip.motions)
        if out.stable and not (material == "plasticine" and _left_alone_reaches(body, out.cloud)):
            cases.append(DeformableCase(material, split, body, manip, out.cloud))
    return cases


def _left_alone_reaches(body: DeformableBody, target: np.ndarray) -> bool:
    """Whether the body with nothing done to it (settling on its board) already reaches ``target`` (N, 3): a press
    that springs back whole leaves no task (measured: 1 of 20 unseen presses, which a random answer then 'reached')."""
    return simulate(body, np.zeros(0, dtype=np.int64), np.zeros((0, 3))).reaches(body, target)


def _random_points(body: DeformableBody, count: int, rng: np.random.Generator) -> np.ndarray:
    from manifoundation.core.deformable.answer import spread_indices

    return spread_indices(body.points, np.arange(len(body.points)), count, rng)


def _score(case: DeformableCase, contacts: np.ndarray, motions: np.ndarray) -> ShapeScore:
    return simulate(case.body, contacts, motions).score(case.body, case.target)


def evaluate_case(case: DeformableCase, methods: tuple[str, ...], contacts: int, rng: np.random.Generator,
                  network: Answer | None = None, corrections: int = 4, service: Mapping[str, Answers] | None = None,
                  ) -> list[MethodResult]:  # fmt: skip
    """Every method of ``methods`` on one case (``network`` needs the callable: case → contacts, motions, source;
    ``corrections``: the rollouts ``moving_corrected`` may spend; the `SERVICE_METHODS` need their callables in
    ``service``, `research.evaluation.deformable_service.service_answers`)."""
    from manifoundation.core.deformable.answer import moving_indices

    target_motion = case.target - case.body.points
    rand = _random_points(case.body, contacts, rng)
    moving = moving_indices(case.body.points, np.arange(len(case.body.points)), target_motion, contacts)
    out = []
    for method in methods:
        if method == "random_motion":
            d = rng.normal(size=(len(rand), 3))
            d /= np.linalg.norm(d, axis=1, keepdims=True)
            d *= rng.uniform(0, np.linalg.norm(target_motion, axis=1).max(), size=(len(rand), 1))
            out.append(MethodResult(method, _score(case, rand, d), len(rand)))
        elif method == "random_target_motion":
            out.append(MethodResult(method, _score(case, rand, target_motion[rand]), len(rand)))
        elif method == "moving_target_motion":
            out.append(MethodResult(method, _score(case, moving, target_motion[moving]), len(moving)))
        elif method == "moving_corrected":
            points, motions = corrected_answer(case, moving, corrections)
            out.append(MethodResult(method, _score(case, points, motions), len(moving)))
        elif method == "ground_truth":
            m = case.manipulation
            out.append(MethodResult(method, _score(case, m.contacts, m.motions), len(m.contacts)))
        elif method == "ground_truth_cut":
            m = case.manipulation
            keep = np.argsort(-np.linalg.norm(target_motion[m.contacts], axis=1), kind="stable")[:contacts]
            out.append(MethodResult(method, _score(case, m.contacts[keep], m.motions[keep]), len(keep)))
        elif method == "network":
            if network is None:
                raise ValueError("methods: 'network' needs a predictor")
            answer = network(case)
            readback = _head_readback(case, answer)
            out.append(MethodResult(method, _score(case, answer.points, answer.motions), len(answer.points),
                                    answer.source, readback))  # fmt: skip
        elif method in SERVICE_METHODS:
            if service is None or method not in service:
                raise ValueError(f"methods: {method!r} needs the service's answers (and a predictor for the network)")
            answers = service[method](case)
            scores = [_score(case, a.points, a.motions) for a in answers]
            rate = float(np.mean([s.success for s in scores])) if method == "network_samples" else None
            first = answers[0]
            out.append(MethodResult(method, scores[0], len(first.points), first.source, _head_readback(case, first),
                                    rate))  # fmt: skip
        else:
            raise ValueError(f"methods: unknown {method!r} (one of {', '.join(METHODS)})")
    return out


Answer = Callable[[DeformableCase], Proposal]


def _head_readback(case: DeformableCase, answer: Proposal) -> float:
    if answer.source != "network" or answer.estimate is None:
        return float("nan")
    return motion_readback(case, answer.points, answer.estimate)


def motion_readback(case: DeformableCase, points: np.ndarray, motions: np.ndarray) -> float:
    """Median over contacts (H, 3) of |motion| / |the target's displacement at the nearest cloud point|: given the
    head's own estimate (`deformable_service.head_estimate`), 1 when its maps read the target's length back (what
    found round 12's short motions); the service's answers move by the displacement itself, so theirs is 1."""
    nearest = contact_vertices(case.body, points)
    target = np.linalg.norm((case.target - case.body.points)[nearest], axis=1)
    return float(np.median(np.linalg.norm(motions, axis=1) / np.maximum(target, 1e-12)))


def corrected_answer(case: DeformableCase, contacts: np.ndarray, corrections: int) -> tuple[np.ndarray, np.ndarray]:
    """The service's answer for given contact indices (H,): their points (H, 3) and motions (H, 3), corrected by
    up to ``corrections`` rollouts on the body it rebuilds from the case's cloud."""
    from manifoundation.core.pipeline import SynthesisInput, TaskInput, run_pipeline
    from manifoundation.core.robots import get_hand

    body = case.body
    inp = SynthesisInput(
        points=body.points, hand=get_hand("panda_gripper"),
        task=TaskInput("point_motion", motion=case.target - body.points), normals=body.normals,
        material=body.material, properties=dict(body.properties), method="contacts", contacts=body.points[contacts],
        handless=True, num_contacts=len(contacts), simulate_rollout=True, rollout_corrections=corrections,
    )  # fmt: skip
    p = run_pipeline(inp).proposals[0]
    assert p.contact_motions is not None
    return np.asarray(p.contact_points), np.asarray(p.contact_motions)


def pipeline_network(predictor: ContactPredictor, hand: Hand, seed: int) -> Answer:
    """The service's answer for a case: `run_pipeline` with method "network", first proposal."""

    def answer(case: DeformableCase) -> Proposal:
        return ask_service(case, predictor, hand, seed, "network", 1, False)[0]

    return answer
