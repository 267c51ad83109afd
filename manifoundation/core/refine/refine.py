"""The iterative SOCP refinement loop (paper §III-B) with an adaptive trust region.

Each iteration: linearise at q (kinematics, Φ, optimal forces f* → r*), solve the step of `.step`, evaluate the
true merit ``‖r*‖² + λ Σ Φ(p_i)² + ρ (Σ penetration + Σ self-overlap)`` at q + δq, accept the step
if it lowers the merit, grow the trust region after good agreement with the model (ratio > 0.75) and shrink it
after a rejection or poor agreement (ratio < 0.25). Adaptive steps are measured better than fixed ones in
`mani-lab bench refine` (fewer iterations, more successes). Convergence (paper): ‖r*‖ < 1e-6 and every |Φ(p_i)|
< 5 mm, and in addition no sphere penetration or self-overlap beyond 1 mm (the step's constraints are only
linearised, so we check them). Where the object's mesh is known, a convergence must also hold on the mesh's
contacts, and a caller's verification can end an attempt that nearly converged (`.ending`).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from manifoundation.core.errors import Cancelled
from manifoundation.core.refine.contact import ObjectField
from manifoundation.core.refine.ending import Endings
from manifoundation.core.refine.forces import DEFAULT_MAX_NORMAL_FORCE
from manifoundation.core.refine.result import IterationRecord as IterationRecord
from manifoundation.core.refine.result import RefineResult as RefineResult
from manifoundation.core.refine.state import HandPose, Linearisation, linearise
from manifoundation.core.refine.step import StepParams, solve_step, solve_step_cvxpy
from manifoundation.core.refine.wrench import WrenchTask

if TYPE_CHECKING:
    from manifoundation.core.robots.hand import Hand


@dataclass(frozen=True)
class RefineConfig:
    """Refinement settings. Why each default is what it is, with the measurements: research/results/refinement.md.

    Attributes:
        max_iterations: at most this many SCP steps (paper: 100).
        residual_tol: ‖r*‖ below this counts as producing the wrench (paper: 1e-6).
        tip_tol: every |Φ(p_i)| below this (m) at convergence. Tighter than verification's 5 mm: Φ is measured on
            the point cloud, which can differ from the exact mesh distance by a few mm on curved faces.
        contact_tol: every contact sample's |Φ − standoff| below this (m) at convergence; None: ``tip_tol``. The
            contact is a pad sample up to ``CONTACT_TIE`` (1.5 mm) farther than the pad's nearest one
            (`manifoundation.core.refine.contact`), so a ``tip_tol`` under that tie (the closing stage's 0.3 mm)
            can leave a pad whose nearest sample touches unconverged for good: the closing stage keeps the main
            stage's 2 mm here.
        region_point_tol: with a region mask, every contact within this of an allowed sample (m); tighter than
            verification's 5 mm for the same reason (Φ^R measures to the samples' discs).
        penetration_tol: guard penetration / self-overlap allowed at convergence (m): half of verification's 1 mm.
        max_normal_force: bound on each normal force (unit target wrench).
        tip_weight: λ (1/m²) on the squared tip distances.
        penalty: ρ on constraint slacks and in the merit.
        merit_slack: penetration and self-overlap the merit lets pass (m), far inside ``penetration_tol``, so that
            the guards' curvature (a few µm) does not reject steps that make progress near the surface.
        trust_translation, trust_rotation, trust_joint, trust_force: the initial trust region s_q, s_f.
        adaptive, trust_grow, trust_shrink, trust_max_scale, trust_min_scale: the adaptive trust region;
            ``adaptive=False`` keeps the initial region (the paper's fixed s_q, s_f).
        stall_window, stall_tolerance: stop ("stalled") when the merit fell by less than this fraction over the
            last ``stall_window`` iterations (a local minimum).
        stuck_window, stuck_tolerance, stuck_penetration: stop sooner when the hand is stuck in the object: a
            guard deeper than ``stuck_penetration`` (m) and the merit fell by less than ``stuck_tolerance`` over
            the last ``stuck_window`` iterations (another approach, not more iterations, frees such an attempt).
        touch_weight, touch_distance: while a tip is farther than ``touch_distance`` (m), the wrench residual is
            weighted by ``touch_weight`` in the merit and the step, so the fingers close first (a far finger's
            contact hops between faces and the residual jumps with it); 1 turns this off.
        verify_within: with an ``accept`` test (verification), it is asked once an iterate meets the convergence
            test with this tip tolerance instead of ``tip_tol`` (`manifoundation.core.refine.ending`).
        solver: ``"clarabel"`` (native, default) or ``"cvxpy"`` (the reference, slow).
        history: keep per-iteration records.
    """

    max_iterations: int = 100
    residual_tol: float = 1e-6
    tip_tol: float = 2e-3
    contact_tol: float | None = None
    region_point_tol: float = 4.5e-3
    penetration_tol: float = 5e-4
    max_normal_force: float = DEFAULT_MAX_NORMAL_FORCE
    tip_weight: float = 100.0
    penalty: float = 10.0
    trust_translation: float = 0.01
    trust_rotation: float = 0.1
    trust_joint: float = 0.15
    trust_force: float = 0.25
    adaptive: bool = True
    trust_grow: float = 2.0
    trust_shrink: float = 0.4
    trust_max_scale: float = 4.0
    trust_min_scale: float = 1.0 / 256
    stall_window: int = 8
    stall_tolerance: float = 0.02
    stuck_window: int = 3
    stuck_tolerance: float = 0.1
    stuck_penetration: float = 1e-3
    merit_slack: float = 5e-5
    touch_weight: float = 0.03
    touch_distance: float = 3e-3
    verify_within: float = 4e-3
    solver: str = "clarabel"
    history: bool = False


def merit(lin: Linearisation, cfg: RefineConfig, weight: float = 1.0) -> float:
    """The true merit the trust region compares against the model's objective (penetrations and overlaps
    counted beyond ``cfg.merit_slack``; the residual's square weighted by ``weight``)."""
    slack = cfg.merit_slack
    return float(
        weight * lin.residual_norm**2
        + cfg.tip_weight * np.sum(lin.tip_phi**2)
        + cfg.penalty * (np.maximum(lin.penetration() - slack, 0.0).sum()
                         + np.maximum(lin.self_overlap() - slack, 0.0).sum())
    )  # fmt: skip


def _stall(merits: list[float], lin: Linearisation, cfg: RefineConfig) -> str:
    """"window": the merit fell by less than ``stall_tolerance`` over the last ``stall_window`` iterations;
    "stuck": by less than ``stuck_tolerance`` over ``stuck_window`` with a guard deeper than ``stuck_penetration``;
    "" otherwise."""
    value = merits[-1]
    if len(merits) > cfg.stall_window and value > (1 - cfg.stall_tolerance) * merits[-1 - cfg.stall_window]:
        return "window"
    if (len(merits) > cfg.stuck_window + 1 and value > (1 - cfg.stuck_tolerance) * merits[-1 - cfg.stuck_window]
            and lin.penetration().max(initial=0.0) > cfg.stuck_penetration):  # fmt: skip
        return "stuck"
    return ""


def _touching(lin: Linearisation, cfg: RefineConfig) -> bool:
    return bool(np.max(np.abs(lin.tip_phi)) < cfg.touch_distance)


def _converged(lin: Linearisation, cfg: RefineConfig, tip_tol: float | None = None) -> bool:
    tip_tol = cfg.tip_tol if tip_tol is None else tip_tol
    contact_tol = tip_tol if cfg.contact_tol is None else max(cfg.contact_tol, tip_tol)
    return bool(
        lin.residual_norm < cfg.residual_tol
        and np.max(np.abs(lin.tip_phi)) < tip_tol
        and (lin.region_point is None or np.max(lin.region_point) < cfg.region_point_tol)
        and (lin.contact_gap is None or np.max(np.abs(lin.contact_gap)) < contact_tol)
        and lin.penetration().max(initial=0.0) <= cfg.penetration_tol
        and lin.self_overlap().max(initial=0.0) <= cfg.penetration_tol
    )


def refine(
    hand: Hand,
    field_: ObjectField,
    task: WrenchTask,
    start: HandPose,
    mu: float,
    config: RefineConfig | None = None,
    tip_field: Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]] | None = None,
    deadline: float | None = None,
    should_cancel: Callable[[], bool] | None = None,
    progress: Callable[[int, int], None] | None = None,
    accept: Callable[[HandPose], bool] | None = None,
) -> RefineResult:
    """Refine a hand pose so that its fingertips produce ``task`` (paper Eq. 9-16).

    Args:
        hand: a `manifoundation.core.robots.Hand`.
        field_: the object: signed distance, given normals, points (`manifoundation.core.refine.field.PointCloudField`).
        task: target (rigid wrench, joint-space, or force closure).
        start: initial pose.
        mu: friction coefficient.
        config: settings.
        tip_field: Φ^R for masked refinement: ``x (m,3) -> (distance (m,), gradient (m,3))``.
        deadline: `time.monotonic()` value; when passed, the best iterate is returned, not converged.
        should_cancel: checked before every iteration; raises `Cancelled` when it returns true.
        progress: called with (iteration, max_iterations).
        accept: verification of a pose, asked once an iterate nearly converges (`manifoundation.core.refine.ending`); a
        pose
            it accepts ends the refinement with reason "verified" (not ``converged``).

    Returns:
        The result (never raises for an infeasible task: it reports not converged and why).
    """
    cfg = config or RefineConfig()
    t0 = time.perf_counter()
    n = 6 + len(start.q)
    base = np.concatenate([np.full(3, cfg.trust_translation), np.full(3, cfg.trust_rotation),
                           np.full(n - 6, cfg.trust_joint)])  # fmt: skip
    step_fn = solve_step if cfg.solver == "clarabel" else solve_step_cvxpy
    ends = Endings(field_, lambda lin: _converged(lin, cfg), lambda lin: _converged(lin, cfg, cfg.verify_within),
                   accept)  # fmt: skip

    def lin_at(pose: HandPose, jacobian: bool = True) -> Linearisation:
        return linearise(hand, pose, field_, task, mu, cfg.max_normal_force, tip_field, jacobian=jacobian,
                         exact=ends.exact)  # fmt: skip

    pose, lin = start, lin_at(start)
    weight = 1.0 if _touching(lin, cfg) else cfg.touch_weight
    value = merit(lin, cfg, weight)
    scale, history, reason, it = 1.0, [], "max_iterations", 0
    merits = [value]
    for it in range(1, cfg.max_iterations + 1):
        ending = ends.at(lin, pose)
        if ending in ("converged", "verified"):
            reason, it = ending, it - 1
            break
        if ending == "exact":  # converged on projected contacts whose mesh contacts cannot hold the wrench
            lin = lin_at(pose)
            weight, value = 1.0, merit(lin, cfg)
            merits = [value]
        if weight != 1.0 and _touching(lin, cfg):  # every finger near: the full merit from here
            weight, value = 1.0, merit(lin, cfg)
            merits = [value]
        if should_cancel is not None and should_cancel():
            raise Cancelled("refinement cancelled")
        if deadline is not None and time.monotonic() >= deadline:
            reason, it = "deadline", it - 1
            break
        ti = time.perf_counter()
        used_scale = scale
        params = StepParams(
            trust=base * scale, trust_force=cfg.trust_force * scale, tip_weight=cfg.tip_weight, penalty=cfg.penalty,
            residual_weight=weight,
        )
        step = step_fn(lin, params)
        accepted = False
        if step.delta is None:
            if scale <= cfg.trust_min_scale:
                reason = f"solver_failed: {step.status}"
                break
            scale = max(scale * cfg.trust_shrink, cfg.trust_min_scale)
        else:
            cand_pose = pose.step(hand, step.delta)
            cand = lin_at(cand_pose, jacobian=False)  # its Jacobians only if it is accepted
            new_value = merit(cand, cfg, weight)
            predicted = value - step.objective
            ratio = (value - new_value) / predicted if predicted > 1e-15 else 0.0
            if new_value < value:
                pose, lin, value, accepted = cand_pose, cand.completed(), new_value, True
            if cfg.adaptive:
                if not accepted or ratio < 0.25:
                    scale = max(scale * cfg.trust_shrink, cfg.trust_min_scale)
                elif ratio > 0.75:
                    scale = min(scale * cfg.trust_grow, cfg.trust_max_scale)
            # a collapsed trust region, or a refused step whose region stays the same: the next step would be
            # this one again (same linearisation, same region, a deterministic solver; 3.5-5 % of all iterations
            # were such repeats)
            collapsed = scale <= cfg.trust_min_scale and predicted <= 1e-12
            if not accepted and (collapsed or scale == used_scale):
                if weight != 1.0:  # the fingers stopped closing: the full merit from here
                    weight, value, scale = 1.0, merit(lin, cfg), 1.0
                    merits = [value]
                    continue
                reason = "stalled"
                break
        merits.append(value)
        stall = _stall(merits, lin, cfg)
        if stall == "window" and weight != 1.0:
            weight, value = 1.0, merit(lin, cfg)
            merits = [value]
            continue
        if stall:
            reason = "stalled"
            break
        if cfg.history:
            history.append(
                IterationRecord(
                    it,
                    lin.residual_norm,
                    float(np.max(np.abs(lin.tip_phi))),
                    float(lin.penetration().max(initial=0.0)),
                    float(lin.self_overlap().max(initial=0.0)),
                    value,
                    scale,
                    accepted,
                    time.perf_counter() - ti,
                )
            )
        if progress is not None:
            progress(it, cfg.max_iterations)
    reason = ends.final(reason, lin)
    return RefineResult(
        pose=pose,
        forces=lin.forces.copy(),
        tips=lin.tips.copy(),
        contacts=lin.tips.copy(),
        normals=lin.normals.copy(),
        residual_norm=lin.residual_norm,
        max_tip_distance=float(np.max(np.abs(lin.tip_phi))),
        penetration=float(lin.penetration().max(initial=0.0)),
        self_overlap=float(lin.self_overlap().max(initial=0.0)),
        converged=reason == "converged",
        reason=reason,
        iterations=it,
        seconds=time.perf_counter() - t0,
        history=history,
    )

