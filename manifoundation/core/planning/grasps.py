"""Contacts along a plan: one synthesis (`manifoundation.core.pipeline.run_pipeline`) per step, keeping the grasp while
it still works.

Step k moves the object from ``poses[k]`` to ``poses[k + 1]``; its task is that motion (the moved points as
``target_points``: the pipeline fits the rigid motion exactly and turns it into the wrench, Eq. 4-5), asked
with the object placed at ``poses[k]`` (world frame). For each step:

1. **keep**: the previous step's hand pose, carried rigidly with the object to ``poses[k]``, is the refinement's
   start (``SynthesisInput.initial_pose``). When the refined pose passes the pipeline's verification (the one a
   single request gets), its hand is collision-free with the scene at both poses of the step (the hand moves with
   the object), and no contact moved more than ``max_contact_shift`` on the object, the grasp is **kept**. A grasp
   that still produces the wrench converges at once (no iteration: the same contacts).
2. **new grasp** otherwise (``"new"`` for the first, ``"regrasp"`` after a held one): the pipeline runs as for a
   single request (``num_proposals``, the plan's method, seed + k; ``new_grasp_attempts`` seeds); of its verified,
   collision-free proposals the one whose hand, carried along the next ``lookahead`` poses, stays clear of the
   scene longest is chosen (the grasp the scene lets be kept longest). If none, a carried grasp that works but
   slid farther than ``max_contact_shift`` is taken as the regrasp; else the step is **failed** and the next one
   starts afresh.
"""

from __future__ import annotations

import time
from dataclasses import replace

import numpy as np

from manifoundation.core.pipeline import ProposalOutput, SynthesisInput, TaskInput, run_pipeline
from manifoundation.core.pipeline.run import CancelCheck
from manifoundation.core.planning.poses import Pose
from manifoundation.core.planning.scene import CollisionScene
from manifoundation.core.planning.types import GraspChange, PlanInput, PlanStep, Progress
from manifoundation.core.refine.state import HandPose
from manifoundation.core.robots.hand import Hand


def step_input(inp: PlanInput, a: Pose, b: Pose, seed: int) -> SynthesisInput:
    """The single synthesis request of the step a → b, the object placed at ``a`` (world frame)."""
    opt = inp.options
    verts = None if inp.mesh_vertices is None else a.apply(inp.mesh_vertices)
    return SynthesisInput(
        points=a.apply(inp.points),
        normals=None if inp.normals is None else a.rotate(inp.normals),
        hand=inp.hand,
        task=TaskInput("target_points", targets=b.apply(inp.points)),
        properties=dict(inp.properties),
        mask=inp.mask,
        mesh_vertices=verts,
        mesh_faces=inp.mesh_faces,
        method=opt.method,
        num_proposals=opt.num_proposals,
        max_iterations=opt.max_iterations,
        seed=seed,
        deadline=opt.deadline,
        hand_key=inp.hand_key,
    )


def palm(p: ProposalOutput) -> Pose:
    """The proposal's palm pose (world)."""
    return Pose(np.asarray(p.palm_position, dtype=np.float64), np.asarray(p.palm_quaternion, dtype=np.float64))


def carried(p: ProposalOutput, a: Pose, b: Pose) -> HandPose:
    """The proposal's hand moved rigidly with the object from ``a`` to ``b`` (fingers unchanged)."""
    moved = palm(p).carry(a, b)
    return HandPose(moved.position, moved.quaternion, np.asarray(p.joint_values, dtype=np.float64).copy())


def hand_hits(scene: CollisionScene, hand: Hand, p: ProposalOutput, a: Pose, b: Pose) -> list[str]:
    """What the proposal's hand meets at the step's start (its own pose) and end (carried to ``b``)."""
    at_b = carried(p, a, b)
    hits = scene.hand_hits(hand, palm(p), p.pose().q)
    hits += [h for h in scene.hand_hits(hand, Pose(at_b.palm_pos, at_b.palm_quat), at_b.q) if h not in hits]
    return hits


def contact_shift(previous: ProposalOutput, prev_pose: Pose, current: ProposalOutput, pose: Pose) -> float:
    """The largest move (m) of a fingertip's contact on the object between two answers (body frame)."""
    before = prev_pose.inverse().apply(previous.contact_points)
    after = pose.inverse().apply(current.contact_points)
    if before.shape != after.shape:
        return float("inf")
    return float(np.linalg.norm(after - before, axis=1).max(initial=0.0))


def reach(scene: CollisionScene, hand: Hand, p: ProposalOutput, poses: list[Pose], k: int, lookahead: int) -> int:
    """How many of the poses after ``poses[k]`` (up to ``lookahead``) the hand, carried, passes collision-free."""
    count = 0
    for j in range(k + 1, min(len(poses), k + 1 + lookahead)):
        h = carried(p, poses[k], poses[j])
        if scene.hand_hits(hand, Pose(h.palm_pos, h.palm_quat), h.q):
            break
        count += 1
    return count


def _new_grasp(
    inp: PlanInput, scene: CollisionScene, poses: list[Pose], k: int, predictor: object | None,
    should_cancel: CancelCheck | None,
) -> tuple[ProposalOutput | None, list[str], int]:  # fmt: skip
    """The best usable new grasp at step k (see module doc), or the best failed one; its hits; pipeline calls."""
    a, b = poses[k], poses[k + 1]
    fallback: tuple[ProposalOutput | None, list[str]] = (None, [])
    for attempt in range(inp.options.new_grasp_attempts):
        seed = inp.options.seed + k + 1000 * attempt
        out = run_pipeline(step_input(inp, a, b, seed), predictor, should_cancel=should_cancel)
        usable = []
        for p in out.proposals:
            hits = hand_hits(scene, inp.hand, p, a, b)
            if p.quality.success and not hits:
                usable.append(p)
            elif fallback[0] is None or (p.quality.success and not fallback[0].quality.success):
                fallback = (p, hits)
        if usable:
            scores = [reach(scene, inp.hand, p, poses, k, inp.options.lookahead) for p in usable]
            return usable[int(np.argmax(scores))], [], attempt + 1
    return fallback[0], fallback[1], inp.options.new_grasp_attempts


def synthesise_along(
    inp: PlanInput, scene: CollisionScene, poses: list[Pose], predictor: object | None = None,
    progress: Progress | None = None, should_cancel: CancelCheck | None = None,
) -> list[PlanStep]:  # fmt: skip
    """The contact answer of every step of ``poses`` (see module doc).

    Raises:
        InvalidInput: the object's arrays (checked by the pipeline). ModelUnavailable: method "network" without
        a predictor. Cancelled: ``should_cancel()`` returned true.
    """
    opt = inp.options
    report = progress or (lambda stage, completed, total: None)
    steps: list[PlanStep] = []
    held: ProposalOutput | None = None
    total = len(poses) - 1
    report("contacts", 0, total)
    for k in range(total):
        a, b = poses[k], poses[k + 1]
        if opt.deadline is not None and time.monotonic() >= opt.deadline:
            steps.append(PlanStep(k, None, "failed"))
            held = None
            continue
        t0, calls, slid, dropped = time.perf_counter(), 0, None, ""
        step: PlanStep | None = None
        if held is not None:
            start = carried(held, poses[k - 1], a)
            out = run_pipeline(replace(step_input(inp, a, b, opt.seed + k), initial_pose=start, num_proposals=1),
                               predictor, should_cancel=should_cancel)  # fmt: skip
            calls += 1
            p = out.proposals[0]
            shift = contact_shift(held, poses[k - 1], p, a)
            hits = hand_hits(scene, inp.hand, p, a, b) if p.quality.success else []
            if not p.quality.success:
                dropped = f"verification: {', '.join(p.quality.failures)}"
            elif hits:
                dropped = f"hand meets {', '.join(hits)}"
            elif shift > opt.max_contact_shift:
                dropped = f"contacts slid {1000 * shift:.1f} mm"
                slid = PlanStep(k, p, "regrasp", shift, dropped=dropped)
            else:
                step = PlanStep(k, p, "kept", shift)
        if step is None:
            found, hits, n = _new_grasp(inp, scene, poses, k, predictor, should_cancel)
            calls += n
            change: GraspChange = "new" if held is None else "regrasp"
            if found is not None and found.quality.success and not hits:
                step = PlanStep(k, found, change, dropped=dropped)
            elif slid is not None:
                step = slid
            else:
                step = PlanStep(k, found, "failed", hand_collisions=hits, dropped=dropped)
        step.seconds, step.calls = time.perf_counter() - t0, calls
        held = step.proposal if step.success else None
        steps.append(step)
        report("contacts", k + 1, total)
    return steps
