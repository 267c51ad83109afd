"""What the MCP tools answer: the contract's answers cut down to what an agent reads (plain JSON, rounded).

A whole `SynthesisResult` or `PlanResult` is large (hand spheres per proposal, a pose per step); an agent needs
the verdict, the numbers it acts on and where to look for the rest (the job id for ``get_job``, the viewer URL).
"""

from __future__ import annotations

from collections import Counter
from typing import Any

import numpy as np

from manifoundation.contract import (
    BatchPublic,
    ErrorBody,
    JobPublic,
    PlanResult,
    Proposal,
    RobotPublic,
    SynthesisResult,
)

MAX_LISTED_STEPS = 60
"""A plan's steps are listed one by one up to this many; beyond, only the changes (new grasps, failures)."""


def _r(values: Any, digits: int = 4) -> Any:
    return np.round(np.asarray(values, dtype=np.float64), digits).tolist()


def error_summary(error: ErrorBody) -> dict[str, Any]:
    """The error as the HTTP API answers it: ``{error, type, detail}``."""
    return error.model_dump(mode="json", exclude_none=True)


def hand_summary(robot: RobotPublic) -> dict[str, Any]:
    """Name, built-in or registered, DoF, fingertips."""
    return {"name": robot.name, "builtin": robot.builtin, "dof": robot.dof, "fingertips": list(robot.fingertips)}


def proposal_summary(p: Proposal) -> dict[str, Any]:
    """One hand answer: verdict, contacts and forces, palm pose, joint values, quality figures."""
    q = p.quality
    return {
        "success": q.success, "failures": list(q.failures), "contact_source": p.contact_source,
        "contact_points": _r(p.contact_points), "forces": _r(p.forces, 3), "fingertips": list(p.fingertips),
        "palm_position": _r(p.palm_position), "palm_quaternion": _r(p.palm_quaternion),
        "joint_values": dict(zip(p.joint_names, _r(p.joint_values), strict=True)),
        "wrench_residual": round(q.wrench_residual, 6), "max_tip_distance_m": round(q.max_tip_distance, 5),
        "penetration_m": round(q.penetration_depth, 5), "epsilon": q.epsilon,
        "physics": None if q.physics is None else {"held": q.physics.held, "reason": q.physics.reason,
                                                   "test": q.physics.test},
    }  # fmt: skip


def result_summary(result: SynthesisResult) -> dict[str, Any]:
    """The best proposal in full, the others' verdicts."""
    best = result.best
    return {
        "hand": result.hand, "verified": sum(p.quality.success for p in result.proposals),
        "proposals": len(result.proposals), "best": None if best is None else proposal_summary(best),
        "others": [{"success": p.quality.success, "failures": list(p.quality.failures)}
                   for p in result.proposals if p is not best],
        "seconds": {k: round(v, 3) for k, v in result.timings.items()},
    }  # fmt: skip


def plan_summary(plan: PlanResult) -> dict[str, Any]:
    """Trajectory, repairs, grasps along it (re-grasps, failures) and the first step's grasp."""
    grasps = Counter(s.grasp.value for s in plan.steps)
    steps = plan.steps if len(plan.steps) <= MAX_LISTED_STEPS else [s for s in plan.steps if s.grasp != "kept"]
    first = next((s.proposal for s in plan.steps if s.proposal is not None and s.success), None)
    return {
        "success": plan.success, "hand": plan.hand, "poses": len(plan.positions),
        "waypoints": [{"index": i, "position": _r(plan.positions[i]), "quaternion": _r(plan.quaternions[i])}
                      for i in plan.waypoint_indices],
        "repairs": [{"waypoint": r.index, "moved_m": round(r.distance, 4), "out_of": r.obstacles,
                     "to": _r(r.repaired.position)} for r in plan.repairs],
        "segments_planned": sum(not s.straight for s in plan.segments), "segments": len(plan.segments),
        "steps": len(plan.steps), "grasps": dict(grasps), "kept_share": round(plan.kept_share, 3),
        "regrasps": plan.regrasps, "failed_steps": [s.index for s in plan.steps if not s.success],
        "step_list": [{"index": s.index, "grasp": s.grasp.value, "success": s.success,
                       **({"dropped": s.dropped} if s.dropped else {}),
                       **({"hand_collisions": s.hand_collisions} if s.hand_collisions else {})} for s in steps],
        "first_grasp": None if first is None else proposal_summary(first),
        "seconds": {k: round(v, 3) for k, v in plan.timings.items()},
    }  # fmt: skip


def job_summary(job: JobPublic, view_url: str | None = None) -> dict[str, Any]:
    """State and progress; when ended, the answer's summary or the error."""
    progress = job.progress.model_dump(mode="json", exclude_none=True)
    out: dict[str, Any] = {"job_id": job.id, "kind": job.kind.value, "state": job.state.value, "progress": progress}
    if view_url:
        out["view_url"] = view_url
    if job.result is not None:
        out["result"] = result_summary(job.result)
    if job.plan is not None:
        out["plan"] = plan_summary(job.plan)
    if job.error is not None:
        out["error"] = error_summary(job.error)
    if not job.state.terminal:
        out["hint"] = "still running: call get_job with this job_id (wait_s up to 60) to follow it"
    return out


def batch_summary(batch: BatchPublic) -> dict[str, Any]:
    """Counts by state and the page's items (verdict of each finished one)."""
    items = []
    for item in batch.items:
        entry: dict[str, Any] = {"index": item.index, "job_id": item.job_id, "state": item.state.value}
        if item.result is not None:
            best = item.result.best
            entry["verified"] = sum(p.quality.success for p in item.result.proposals)
            entry["best"] = None if best is None else proposal_summary(best)
        if item.error is not None:
            entry["error"] = error_summary(item.error)
        items.append(entry)
    return {
        "batch_id": batch.id, "total": batch.total, "done": batch.done,
        "counts": {str(k): v for k, v in batch.counts.items()}, "offset": batch.offset, "items": items,
    }  # fmt: skip
