"""The service's deformable answers with K proposals, for `research.evaluation.deformable` (methods
``network_samples``, ``network_checked``, ``random_checked``).

One latent sample is a noisy measure of the network: at 20 cases a row, the first proposal's success moves by
5-10 points between seeds while the network does not change. The methods here ask the service
(`manifoundation.core.pipeline.run_pipeline`, what a caller gets) for ``proposals`` = K answers at once:

- ``network_samples``: the K network proposals, each simulated on the case's own body; the case's success is
  the fraction that reach the target (the network's per-sample success rate, the noise of one draw averaged).
- ``network_checked``: the same request with ``simulate_rollout``: the service rebuilds the body from the cloud,
  simulates each proposal (and the most-moved points beside them), and returns the best by its rollout first;
  that first answer is then simulated on the case's own body. The deformable counterpart of network +
  refinement: the service's physics picks, an independent body judges.
- ``random_checked``: the same budget for random contacts (K spread points with the target's motion at them,
  method ``random_contacts``), picked by the same rollout: the equal-budget baseline of ``network_checked``.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, NamedTuple, Protocol

import numpy as np

from manifoundation.core.deformable.body import DeformableBody

if TYPE_CHECKING:
    from manifoundation.core.network.inference import ContactPredictor
    from manifoundation.core.robots import Hand

SERVICE_METHODS = ("network_samples", "network_checked", "random_checked")


class Proposal(NamedTuple):
    """One answer of the service.

    Attributes:
        points: (H, 3) contact points. motions: (H, 3) their post-contact motions, m. source: network,
            motion_fallback, random, ...
        estimate: (H, 3) the network's own estimate of each contact's motion (motion map / heat at the contact,
            `head_estimate`), where the output carries the maps of the sample the answer came from (the first
            answer of an unchecked request); None otherwise. The answer's motions are the task's displacement
            there, so only this says what the head has learnt about motion.
    """

    points: np.ndarray
    motions: np.ndarray
    source: str
    estimate: np.ndarray | None = None


class Case(Protocol):
    """What a request is made of: the body at rest and the target cloud (N, 3) (`deformable.DeformableCase`)."""

    body: DeformableBody
    target: np.ndarray


Answers = Callable[[Case], list[Proposal]]


def ask_service(case: Case, predictor: ContactPredictor | None, hand: Hand, seed: int, method: str,
                proposals: int, checked: bool) -> list[Proposal]:  # fmt: skip
    """The service's answers (`run_pipeline`) to the case's request: its cloud with the target's per-point motion.

    Args:
        case: the body and target. predictor: the network (used by method "network" only). hand: the robot.
        seed: the request's seed. method: the request's method. proposals: K. checked: ``simulate_rollout``.
    """
    from manifoundation.core.deformable.simulate import contact_vertices
    from manifoundation.core.pipeline import SynthesisInput, TaskInput, run_pipeline

    body = case.body
    inp = SynthesisInput(points=body.points, hand=hand, normals=body.normals,
                         task=TaskInput("point_motion", motion=case.target - body.points),
                         material=body.material, properties=dict(body.properties), method=method,
                         num_proposals=proposals, seed=seed, simulate_rollout=checked)  # fmt: skip
    out = run_pipeline(inp, predictor if method == "network" else None)
    answers = []
    for k, p in enumerate(out.proposals):
        assert p.contact_motions is not None
        points = np.asarray(p.contact_points)
        estimate = None
        # without a rollout the k-th answer is the k-th latent sample's, and the output holds sample 0's maps
        if k == 0 and not checked and p.contact_source == "network" and out.heatmap is not None \
                and out.force_map is not None:  # fmt: skip
            estimate = head_estimate(out.heatmap, out.force_map, contact_vertices(body, points))
        answers.append(Proposal(points, np.asarray(p.contact_motions), p.contact_source, estimate))
    return answers


def head_estimate(heatmap: np.ndarray, motion_map: np.ndarray, indices: np.ndarray) -> np.ndarray:
    """The network's own motion (H, 3) at the contacts ``indices`` (H,): its motion map (N, 3) over its heat (N,)
    there, the heat floored at `HEAT_FLOOR` (the quotient the read-out loss trains)."""
    from manifoundation.core.network.selection import HEAT_FLOOR

    heat = np.maximum(np.asarray(heatmap, dtype=np.float64)[indices], HEAT_FLOOR)
    estimate: np.ndarray = np.asarray(motion_map, dtype=np.float64)[indices] / heat[:, None]
    return estimate


def service_answers(predictor: ContactPredictor | None, hand: Hand, seed: int, proposals: int
                    ) -> dict[str, Answers]:  # fmt: skip
    """The callables of `SERVICE_METHODS` (the network's two need ``predictor``; without one only
    ``random_checked`` is there).

    Args:
        predictor: the network. hand: the robot (H ≤ its fingertips). seed: the requests' seed.
        proposals: K answers per request.
    """
    if proposals < 1:
        raise ValueError(f"proposals must be ≥ 1, got {proposals}")

    def ask(case: Case, method: str, checked: bool) -> list[Proposal]:
        return ask_service(case, predictor, hand, seed, method, proposals, checked)

    methods: dict[str, Answers] = {"random_checked": lambda case: ask(case, "random_contacts", True)[:1]}
    if predictor is not None:
        methods["network_samples"] = lambda case: ask(case, "network", False)
        methods["network_checked"] = lambda case: ask(case, "network", True)[:1]
    return methods
