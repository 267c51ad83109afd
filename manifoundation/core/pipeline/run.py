"""`run_pipeline`: contacts → initial pose → SOCP refinement → verification, with progress, cancel, deadline.

Stages reported to ``progress(stage, fraction)``: "network", "initialisation", "refinement" (k / max iterations over all
proposals), "verification". ``should_cancel()`` is checked between stages and before every refinement iteration (raises
`Cancelled`). A ``deadline`` (time.monotonic()) that passes during refinement stops it and returns the best iterate, not
converged, reason "deadline"; later proposals are then not refined. For methods "network" and "random_contacts" a
refinement that stalls is restarted from approach alignments (`manifoundation.core.refine.strategy`) within the same
iteration budget; given contacts ("contacts") are never abandoned. Deformable materials (cloth, rope, plasticine) with a
per-point task (``point_motion``, ``target_points``) get contacts with a post-contact motion each and no refinement
(`manifoundation.core.pipeline.deformable`); with other tasks they are handled as rigid bodies for the hand (the motion
fitted rigidly, Kabsch).

Why one module: the stages of one request (network, contact sets, initialisation, refinement, verification)
run in order on one `Prepared` and share its timings and cancellation checks.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import replace
from typing import Any

import numpy as np

from manifoundation.core.pipeline.deformable import (
    PreparedDeformable,
    finish_deformable,
    is_deformable_task,
    network_input,
    prepare_deformable,
)
from manifoundation.core.pipeline.object_cache import ObjectCache
from manifoundation.core.pipeline.physics_search import PhysicsJudge, best_by_physics, enough_held
from manifoundation.core.pipeline.prepare import ContactSet, Prepared, contact_sets, network_inputs, prepare
from manifoundation.core.pipeline.types import (
    Cancelled,
    InvalidInput,
    IterationOutput,
    ModelUnavailable,
    ProposalOutput,
    QualityOutput,
    SynthesisInput,
    SynthesisOutput,
)
from manifoundation.core.refine.baseline import direct_grasp
from manifoundation.core.refine.close import close_gaps
from manifoundation.core.refine.initialise import initialise, rest_geometry
from manifoundation.core.refine.refine import RefineConfig, refine
from manifoundation.core.refine.squeeze import squeeze_imbalance
from manifoundation.core.refine.state import HandPose
from manifoundation.core.refine.strategy import refine_from_start
from manifoundation.core.refine.verify import Verification, verify

GIVEN_TOLERANCE = 0.005  # m: a given contact that moved farther is reported "given_moved", not "given"
Progress = Callable[[str, float], None]
CancelCheck = Callable[[], bool]


def _check(should_cancel: CancelCheck | None) -> None:
    if should_cancel is not None and should_cancel():
        raise Cancelled("synthesis cancelled")


def _network(batch: Sequence[Prepared | PreparedDeformable], predictor: Any) -> list[Any]:
    """One predictor call for every network input of the batch (grouped by K); returns outputs in order."""
    outputs: list[Any] = [None] * len(batch)
    by_k: dict[int, list[int]] = {}
    for i, prep in enumerate(batch):
        if prep.inp.method == "network" and prep.inp.initial_pose is None:
            by_k.setdefault(prep.inp.candidates, []).append(i)
    if by_k and predictor is None:
        raise ModelUnavailable("method 'network' needs a trained model; none is loaded (use 'contacts')")
    for k, idx in by_k.items():
        rows = [network_input(p) if isinstance(p, PreparedDeformable) else network_inputs([p])[0]
                for p in (batch[i] for i in idx)]  # fmt: skip
        res = predictor.predict(rows, num_samples=k,
                                seed=[batch[i].inp.seed for i in idx])
        for i, out in zip(idx, res, strict=True):
            outputs[i] = out
    return outputs


def _start_pose(prep: Prepared) -> HandPose:
    """Direct-grasp start: palm 10 cm outside the object along a seeded direction, facing its centre."""
    from scipy.spatial.transform import Rotation

    rng = np.random.default_rng(prep.inp.seed)
    d = rng.normal(size=3)
    d /= np.linalg.norm(d)
    hand = prep.inp.hand
    rot = Rotation.align_vectors([-d], [np.asarray(hand.approach_axis, dtype=np.float64)])[0]
    radius = float(np.max(np.linalg.norm(prep.cloud.points - prep.centre, axis=1)))
    quat = rot.as_quat()[[3, 0, 1, 2]]
    return HandPose(prep.centre + d * (radius + 0.1), quat, np.asarray(hand.rest, dtype=np.float64).copy())


class _Verifier:
    """Verification of the poses one request asks about, each once: a stalled attempt's pose is verified before
    any restart (`_refined`), and the proposal's own verification reuses it. The refinement's questions
    (``complete=False``) stop at a failed contact test; the proposal's answer needs every measure, so an
    incomplete one is completed then."""

    def __init__(self, prep: Prepared) -> None:
        self.prep = prep
        self.seen: dict[bytes, Verification] = {}
        inp = prep.inp
        given = inp.method == "contacts" and inp.initial_pose is None and inp.contacts is not None
        self.given = np.asarray(inp.contacts, dtype=np.float64).reshape(-1, 3) if given else None

    def __call__(self, pose: HandPose, complete: bool = True) -> Verification:
        key = np.concatenate([pose.palm_pos, pose.palm_quat, pose.q]).tobytes()
        known = self.seen.get(key)
        if known is None or (complete and not known.complete):
            p = self.prep
            self.seen[key] = verify(
                p.inp.hand, pose, p.cloud, p.task, p.mu, p.mesh, complete=complete, given=self.given
            )
        return self.seen[key]


def _proposal(
    prep: Prepared, pose: HandPose, result: Any, seconds: dict[str, float], source: str, verified: _Verifier
) -> ProposalOutput:
    inp, hand = prep.inp, prep.inp.hand
    t0 = time.perf_counter()
    ver = verified(pose)
    seconds["verification"] = seconds.get("verification", 0.0) + time.perf_counter() - t0
    history = None
    if inp.return_history and result is not None:
        history = [IterationOutput(h.residual_norm, h.max_tip_distance, h.trust_scale) for h in result.history]
    quality = QualityOutput(
        success=ver.success,
        converged=bool(result.converged) if result is not None else False,
        reason=result.reason if result is not None else "not_refined",
        iterations=int(result.iterations) if result is not None else 0,
        wrench_residual=float(ver.residual_norm**2),
        max_tip_distance=ver.max_tip_distance,
        penetration_depth=ver.penetration,
        self_collision_depth=ver.self_collision,
        epsilon=ver.epsilon if prep.task.closure else None,
        failures=list(ver.failures),
        geometry=ver.geometry,
    )
    imbalance = None
    if prep.task.closure and verified.given is None and len(ver.contacts) == hand.num_fingertips:
        imbalance = squeeze_imbalance(hand, pose, ver.contacts, ver.normals, prep.task.centre, prep.task.length)
    shift = None
    if verified.given is not None:  # the caller's contacts: say how far each moved, "given" only if none did
        shift = np.linalg.norm(ver.contacts - verified.given, axis=1)
        source = "given" if float(shift.max()) <= GIVEN_TOLERANCE else "given_moved"
    return ProposalOutput(
        contact_points=ver.contacts,
        contact_normals=ver.normals,
        forces=ver.forces,
        fingertips=ver.links or list(hand.fingertip_links),
        palm_position=pose.palm_pos.copy(),
        palm_quaternion=pose.palm_quat.copy(),
        joint_names=list(hand.joint_names),
        joint_values=pose.q.copy(),
        quality=quality,
        contact_source=source,
        history=history,
        contact_shift=shift,
        squeeze_imbalance=imbalance,
    )


def _finish(
    prep: Prepared, net_out: Any, progress: Progress | None, should_cancel: CancelCheck | None,
    timings: dict[str, float],
) -> SynthesisOutput:
    inp, hand = prep.inp, prep.inp.hand
    report = progress or (lambda stage, fraction: None)
    _check(should_cancel)
    t0 = time.perf_counter()
    starts: list[HandPose] = []
    sources: list[str] = []
    chosen: list[ContactSet | None] = []  # the contact set each start came from (None: no contact search)
    if inp.initial_pose is not None:  # the caller's start (a planner's carried grasp): refined as given
        starts.append(inp.initial_pose)
        sources.append("initial_pose")
    elif inp.method == "direct_grasp":
        for k in range(inp.candidates):
            start = _start_pose(replace(prep, inp=replace(inp, seed=inp.seed + k)))
            starts.append(direct_grasp(hand, prep.cloud, start, prep.centre)[0])
            sources.append("direct_grasp")
    else:
        rest = rest_geometry(hand)
        sets = contact_sets(prep, net_out)
        seen: dict[bytes, int] = {}
        for k, (points, normals, heat, source, _, _) in enumerate(sets):
            # K proposals with the same contacts (identical latent samples, or given contacts) would refine the
            # same start K times: the n-th repeat starts from the n-th best finger assignment instead.
            key = np.round(np.asarray(points, dtype=np.float64), 6).tobytes()
            repeat = seen.get(key, 0)
            seen[key] = repeat + 1
            cand = initialise(hand, prep.cloud, points, normals, predicted=heat, rest=rest, top_k=repeat + 1)
            starts.append(cand[min(repeat, len(cand) - 1)].pose)
            sources.append(source)
            chosen.append(sets[k])
            report("initialisation", (k + 1) / len(sets))
    timings["initialisation"] = time.perf_counter() - t0
    _check(should_cancel)
    config = RefineConfig(max_iterations=inp.max_iterations, history=inp.return_history)
    total = max(1, len(starts) * inp.max_iterations)
    chosen += [None] * (len(starts) - len(chosen))
    proposals: list[ProposalOutput] = []
    seconds: dict[str, float] = {"refinement": 0.0}
    judge = PhysicsJudge(prep) if inp.simulate != "off" else None
    search = inp.simulate == "search"
    for k, (start, source) in enumerate(zip(starts, sources, strict=True)):
        enough = inp.stop_after_verified
        if enough is not None and sum(p.quality.success for p in proposals) >= enough:
            break  # enough verified proposals: the rest are neither refined nor returned
        if search and k >= inp.num_proposals and (enough_held(proposals, inp.num_proposals) or (
                inp.deadline is not None and time.monotonic() >= inp.deadline)):
            break  # searching: enough held (or no time left): no more candidates
        t0 = time.perf_counter()
        verified = _Verifier(prep)
        res = _refined(prep, start, k, config, total, report, should_cancel, verified)
        seconds["refinement"] += time.perf_counter() - t0
        _check(should_cancel)
        proposal = _proposal(prep, res.pose if res is not None else start, res, seconds, source, verified)
        if (picked := chosen[k]) is not None:
            proposal.network_forces, proposal.network_sample = picked.forces, picked.sample
        if search and judge is not None:
            t0 = time.perf_counter()
            proposal.physics = judge(proposal)
            seconds["physics"] = seconds.get("physics", 0.0) + time.perf_counter() - t0
        proposals.append(proposal)
        report("verification", (k + 1) / len(starts))
        _check(should_cancel)
    timings["refinement"] = seconds["refinement"]
    timings["verification"] = seconds.get("verification", 0.0)
    proposals.sort(key=_rank)
    if judge is not None:
        t0 = time.perf_counter()
        if search:
            proposals = best_by_physics(proposals, inp.num_proposals)
            judge.complete_trials(proposals)
        else:  # check: each returned proposal tested once, those that held first
            for p in proposals:
                p.physics = judge(p, complete=True)
            proposals = best_by_physics(proposals, len(proposals))
        timings["physics"] = seconds.get("physics", 0.0) + time.perf_counter() - t0
    heat = force = None
    if net_out is not None:  # the maps of the sample the best proposal came from (the first when none did)
        best = next((p.network_sample for p in proposals if p.network_sample is not None), 0)
        heat, force = net_out.heatmaps[best].astype(np.float64), net_out.force_maps[best].astype(np.float64)
    every = None if net_out is None else np.asarray(net_out.heatmaps, dtype=np.float64)
    return SynthesisOutput(hand=hand.name, proposals=proposals, heatmap=heat, force_map=force, heatmaps=every,
                           timings=timings)  # fmt: skip


def _rank(p: ProposalOutput) -> tuple[bool, float, float]:
    """Verified first; among them (force closure) the better-balanced squeeze first (`squeeze_imbalance`), then
    the larger Ferrari–Canny ε; each group else in order. Of four proposals on 43 third-party objects, the first
    held for LEAP in 10 ordered by the squeeze's balance, 6 by ε; Allegro 5 and 5 (research/results/physics.md)."""
    eps = p.quality.epsilon
    balance = p.squeeze_imbalance if p.squeeze_imbalance is not None else np.inf
    return not p.quality.success, balance, -eps if eps is not None and np.isfinite(eps) else np.inf


def _refined(
    prep: Prepared, start: HandPose, k: int, config: RefineConfig, total: int, report: Progress,
    should_cancel: CancelCheck | None, verified: _Verifier,
) -> Any:
    """Proposal ``k``'s refinement from ``start`` (restarted from approach alignments when it stalls), or None
    when the request asks for no refinement. An attempt that stalls but whose pose verification accepts (the
    SCP's own test is stricter: fingertips within 2 mm on the points' surface, verification's 4 mm on the exact
    geometry) ends the search: a restart would cost 15-30 iterations for a grasp already verified."""
    inp, hand = prep.inp, prep.inp.hand
    if not inp.refine or (inp.method == "direct_grasp" and inp.initial_pose is None):
        return None
    if inp.deadline is not None and time.monotonic() >= inp.deadline:
        return _expired(start)

    def step_done(it: int, cap: int) -> None:
        report("refinement", (k * inp.max_iterations + it) / total)

    def accept(pose: HandPose) -> bool:
        return verified(pose, complete=False).success

    res = refine(
        hand, prep.cloud, prep.task, start, prep.mu, config, tip_field=prep.tip_field, deadline=inp.deadline,
        should_cancel=should_cancel, progress=step_done, accept=accept,
    )
    left = inp.max_iterations - res.iterations
    restart = inp.method != "contacts" and inp.initial_pose is None
    if not res.converged and res.reason != "deadline" and restart and left >= 10 and not accept(res.pose):
        # the initial pose led to a local minimum: restart from approach alignments
        # (manifoundation.core.refine.strategy)
        again = refine_from_start(
            hand, prep.cloud, prep.task, start, prep.mu, replace(config, max_iterations=left),
            seed=inp.seed + k, tip_field=prep.tip_field, deadline=inp.deadline, should_cancel=should_cancel,
            accept=accept, tilts_first=True,
        )
        again.iterations += res.iterations
        if again.converged or accept(again.pose):
            res = again
        else:  # the first attempt's answer stands, but the request spent every attempt's iterations
            res.iterations = again.iterations
    # a caller's start (a planner's carried grasp) was closed when it was found: it stays as carried
    if inp.close_gaps and inp.initial_pose is None and res.reason != "deadline" and verified(res.pose).success:
        res = _closed(prep, res, config, should_cancel, verified)
    return res


def _closed(
    prep: Prepared, res: Any, config: RefineConfig, should_cancel: CancelCheck | None, verified: _Verifier
) -> Any:
    """``res`` with its fingertips closed onto the object (`manifoundation.core.refine.close`: gaps of 1-3 mm at the
    refinement's tip tolerance become ≤ 0.5-1 mm) where verification still accepts the closed pose; else ``res``."""
    inp = prep.inp
    closed = close_gaps(inp.hand, prep.cloud, prep.task, res.pose, prep.mu, config, tip_field=prep.tip_field,
                        deadline=inp.deadline, should_cancel=should_cancel)  # fmt: skip
    if closed.iterations == 0 or not verified(closed.pose).success:
        res.iterations += closed.iterations
        return res
    return replace(res, pose=closed.pose, forces=closed.forces, tips=closed.tips, contacts=closed.contacts,
                   normals=closed.normals, residual_norm=closed.residual_norm,
                   max_tip_distance=closed.max_tip_distance, penetration=closed.penetration,
                   self_overlap=closed.self_overlap, iterations=res.iterations + closed.iterations,
                   seconds=res.seconds + closed.seconds, history=res.history + closed.history)  # fmt: skip


def _expired(start: HandPose) -> Any:
    from manifoundation.core.refine.refine import RefineResult

    z = np.zeros((0, 3))
    return RefineResult(start, z, z, z, z, float("inf"), float("inf"), 0.0, 0.0, False, "deadline", 0, 0.0)


def run_pipeline(
    inp: SynthesisInput,
    predictor: Any | None = None,
    progress: Progress | None = None,
    should_cancel: CancelCheck | None = None,
    cache: ObjectCache | None = None,
) -> SynthesisOutput:
    """Synthesise contacts, forces and hand poses for one request.

    Args:
        inp: the request in core form.
        predictor: object with ``predict(batch, num_samples, seed)`` (`manifoundation.core.network.ContactPredictor`);
            required for method "network".
        progress: ``progress(stage, fraction)`` callback.
        should_cancel: polled between stages and refinement iterations.
        cache: where objects met before are kept (`manifoundation.core.pipeline.object_cache`; default: the process's).

    Returns:
        The output (proposals that fail verification are returned too, marked ``success=False``).

    Raises:
        InvalidInput: malformed arrays or task. ModelUnavailable: "network" without a predictor.
        Cancelled: ``should_cancel()`` returned true.
    """
    out = run_pipeline_batch([inp], predictor, progress, should_cancel, raise_errors=True, cache=cache)[0]
    assert isinstance(out, SynthesisOutput)
    return out


def run_pipeline_batch(
    inputs: Sequence[SynthesisInput],
    predictor: Any | None = None,
    progress: Progress | None = None,
    should_cancel: CancelCheck | None = None,
    raise_errors: bool = False,
    cache: ObjectCache | None = None,
) -> list[SynthesisOutput | Exception]:
    """Run many requests: the network once for the whole batch (micro-batching), then refine each (``cache``:
    as `run_pipeline`'s).

    Returns one entry per input: its output, or (with ``raise_errors=False``) the `InvalidInput` /
    `ModelUnavailable` raised for it, so one bad request does not sink its batch-mates. `Cancelled` always
    propagates.
    """
    report = progress or (lambda stage, fraction: None)
    preps: list[Prepared | PreparedDeformable | Exception] = []
    for inp in inputs:
        try:
            preps.append(prepare_deformable(inp) if is_deformable_task(inp) else prepare(inp, cache))
        except InvalidInput as exc:
            if raise_errors:
                raise
            preps.append(exc)
    _check(should_cancel)
    ok = [p for p in preps if isinstance(p, Prepared | PreparedDeformable)]
    t0 = time.perf_counter()
    report("network", 0.0)
    try:
        net = _network(ok, predictor)
    except ModelUnavailable as exc:
        if raise_errors:
            raise
        net = [exc if p.inp.method == "network" else None for p in ok]
    net_s = time.perf_counter() - t0
    report("network", 1.0)
    results: list[SynthesisOutput | Exception] = []
    j = 0
    for p in preps:
        if isinstance(p, Exception):
            results.append(p)
            continue
        net_out = net[j]
        j += 1
        if isinstance(net_out, Exception):
            results.append(net_out)
            continue
        timings = {"prepare": p.seconds, "network": net_s if p.inp.method == "network" else 0.0}
        try:
            if isinstance(p, PreparedDeformable):
                results.append(finish_deformable(p, net_out, timings))
            else:
                results.append(_finish(p, net_out, progress, should_cancel, timings))
        except InvalidInput as exc:
            if raise_errors:
                raise
            results.append(exc)
        timings["total"] = sum(timings.values())
    return results


__all__ = ["run_pipeline", "run_pipeline_batch"]
