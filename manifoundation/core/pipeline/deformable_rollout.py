"""A deformable answer judged in the simulator: `options.simulate_rollout` (and `options.rollout_corrections`).

The object is rebuilt as a simulation body from its points (`manifoundation.core.deformable.reconstruct`), each
proposal's contacts are grasped and moved by their motions (`manifoundation.core.deformable.simulate`, the same physics
as the data and the evaluation), and the rollout is scored against the target (the points plus the per-point target
motion; for unordered targets, the registered motion) by the paper's shape metric
(`manifoundation.core.deformable.metrics`). The body is rebuilt once per request and shared by the proposals.

Corrections (closed loop through the simulator). The target's displacement at a contact is where that point
ends after the release, not the motion that takes it there: a plasticine press springs back and drags its
neighbours, so pushing by the target's displacement stops short. With ``rollout_corrections`` = C > 0, a
proposal whose rollout misses the target gets up to C more rollouts: its motions d (H × 3) are corrected by
Broyden's method on the contacts' end positions, e(d) = target(contacts) − rollout(contacts) → 0, starting from
the identity Jacobian (the first correction adds the miss to the motion, as iterative learning control does), a
step that ends farther from the target halved once before the next update. The best rollout by the metric
(`metrics.shortfall`) is the proposal's answer, its motions the ones that produced it.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np
from scipy.spatial import cKDTree

from manifoundation.core.pipeline.types import ProposalOutput


@dataclass
class _Trial:
    """One rollout of a proposal's contacts: its motions (H, 3), the cloud it leaves (N, 3), whether the metric
    accepts it (``reached``) and the simulation stayed stable (``success``: both), its rank and shape error."""

    motions: np.ndarray
    rollout: np.ndarray
    stable: bool
    reached: bool
    success: bool
    rank: float
    shape_error: float


def judge_by_rollout(
    material: str, points: np.ndarray, normals: np.ndarray, motion: np.ndarray, properties: dict[str, float],
    proposals: list[ProposalOutput], corrections: int = 0,
) -> list[ProposalOutput]:
    """Each proposal with its rollout, shape error and the metric's verdict as its quality.

    Args:
        material: cloth, rope or plasticine.
        points: (N, 3) the object's points; normals: (N, 3) their outward normals.
        motion: (N, 3) the target motion of every point (target = points + motion).
        properties: the material's properties.
        proposals: answers with ``contact_motions``.
        corrections: rollouts each missing proposal may spend correcting its motions (module doc).

    Raises:
        InvalidInput: the points cannot be rebuilt as that material's body (naming ``object.points``).
    """
    from manifoundation.core.deformable.materials import with_defaults
    from manifoundation.core.deformable.metrics import shape_score, shortfall
    from manifoundation.core.deformable.reconstruct import body_from_cloud
    from manifoundation.core.deformable.simulate import simulate

    rebuilt = body_from_cloud(material, points, normals, with_defaults(material, properties))
    target = points + motion

    def trial(contacts: np.ndarray, motions: np.ndarray) -> _Trial:
        run = simulate(rebuilt.body, rebuilt.to_simulator(contacts), motions)
        rollout = rebuilt.cloud(run.vertices)
        score = shape_score(material, points, target, rollout)
        rank = shortfall(material, score) if run.stable else float("inf")
        return _Trial(motions, rollout, run.stable, score.success, score.success and run.stable, rank,
                      score.top_mean_error)  # fmt: skip

    judged = []
    for p in proposals:
        assert p.contact_motions is not None
        contacts = np.asarray(p.contact_points, dtype=np.float64)
        best, used = trial(contacts, np.asarray(p.contact_motions, dtype=np.float64)), 0
        if corrections > 0 and not best.success:
            at = np.asarray(cKDTree(points).query(contacts)[1], dtype=np.int64)
            best, used = _corrected(trial, best, target, at, contacts, corrections)
        failures = [] if best.reached else ["rollout_target"]
        if not best.stable:
            failures.append("rollout_unstable")
        quality = replace(p.quality, success=best.success, converged=best.stable,
                          reason="rollout_reached_target" if best.success else "rollout_missed_target",
                          failures=failures, iterations=used)  # fmt: skip
        judged.append(replace(p, quality=quality, contact_motions=best.motions, rollout_points=best.rollout,
                              shape_error=best.shape_error))  # fmt: skip
    return sorted(judged, key=lambda q: (not q.quality.success, q.shape_error or 0.0))


def _corrected(
    trial: Callable[[np.ndarray, np.ndarray], _Trial], first: _Trial, target: np.ndarray, at: np.ndarray,
    contacts: np.ndarray, budget: int,
) -> tuple[_Trial, int]:
    """Broyden's corrections of ``first``'s motions (module doc): the best trial and the rollouts spent.

    Args:
        trial: simulates (contacts (H, 3), motions (H, 3)) and scores the rollout.
        first: the uncorrected answer's trial.
        target: (N, 3) the target cloud; at: (H,) the cloud index of each contact.
        contacts: (H, 3) the contact points.
        budget: most rollouts to spend.
    """

    def miss(t: _Trial) -> np.ndarray:
        gap: np.ndarray = (target[at] - t.rollout[at]).reshape(-1)
        return gap

    best, current, used = first, first, 0
    jac = np.eye(3 * len(at))
    e = miss(current)
    while used < budget and not best.success:
        step = np.linalg.solve(jac, e)
        cand = trial(contacts, current.motions + step.reshape(-1, 3))
        used += 1
        e_new = miss(cand)
        if np.linalg.norm(e_new) > np.linalg.norm(e) and used < budget:  # overshot: half the step, once
            step = 0.5 * step
            cand = trial(contacts, current.motions + step.reshape(-1, 3))
            used += 1
            e_new = miss(cand)
        moved = e - e_new  # how far the step moved the contacts' ends
        jac = jac + np.outer(moved - jac @ step, step) / max(float(step @ step), 1e-18)
        if cand.rank < best.rank:
            best = cand
        current, e = cand, e_new
    return best, used
