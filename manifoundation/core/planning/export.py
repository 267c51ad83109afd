"""A plan as plain JSON-ready data, with the field names of the wire answer (``manifoundation/contract/plans.py``:
``PlanResult``), and a short text summary of it."""

from __future__ import annotations

from typing import Any

import numpy as np

from manifoundation.core.pipeline import ProposalOutput
from manifoundation.core.planning.poses import Pose
from manifoundation.core.planning.types import PlanOutput


def pose_dict(pose: Pose) -> dict[str, list[float]]:
    """``{position, quaternion}`` as lists."""
    return {"position": np.asarray(pose.position).tolist(), "quaternion": np.asarray(pose.quaternion).tolist()}


def proposal_dict(p: ProposalOutput) -> dict[str, Any]:
    """One proposal with the wire's field names."""
    q, pose = p.quality, p.pose()
    return {
        "contact_points": p.contact_points.tolist(),
        "contact_normals": p.contact_normals.tolist(),
        "forces": p.forces.tolist(),
        "fingertips": list(p.fingertips),
        "palm_position": pose.palm_pos.tolist(),
        "palm_quaternion": pose.palm_quat.tolist(),
        "joint_names": list(p.joint_names),
        "joint_values": pose.q.tolist(),
        "contact_source": p.contact_source,
        "quality": {
            "success": q.success, "converged": q.converged, "reason": q.reason, "iterations": q.iterations,
            "wrench_residual": q.wrench_residual, "max_tip_distance": q.max_tip_distance,
            "penetration_depth": q.penetration_depth, "self_collision_depth": q.self_collision_depth,
            "epsilon": q.epsilon, "failures": list(q.failures), "geometry": q.geometry,
        },
    }  # fmt: skip


def plan_to_dict(plan: PlanOutput) -> dict[str, Any]:
    """The plan as JSON-ready data (positions (T, 3) and quaternions (T, 4) as nested lists)."""
    return {
        "success": plan.success,
        "positions": [np.asarray(p.position).tolist() for p in plan.poses],
        "quaternions": [np.asarray(p.quaternion).tolist() for p in plan.poses],
        "waypoint_indices": list(plan.waypoint_indices),
        "repairs": [{"index": r.index, "requested": pose_dict(r.requested), "repaired": pose_dict(r.repaired),
                     "distance": r.distance, "obstacles": list(r.obstacles)} for r in plan.repairs],
        "segments": [vars(s).copy() for s in plan.segments],
        "steps": [{"index": s.index, "grasp": s.grasp, "success": s.success, "contact_shift": s.contact_shift,
                   "hand_collisions": list(s.hand_collisions), "dropped": s.dropped, "seconds": s.seconds,
                   "calls": s.calls,
                   "proposal": None if s.proposal is None else proposal_dict(s.proposal)}
                  for s in plan.steps],
        "regrasps": plan.regrasps,
        "kept_share": plan.kept_share,
        "timings": dict(plan.timings),
    }


def summary_lines(plan: PlanOutput) -> list[str]:
    """A few lines: trajectory, repairs, grasps, times."""
    lines = [f"trajectory: {len(plan.poses)} poses through {len(plan.waypoint_indices)} waypoints, "
             f"{sum(not s.straight for s in plan.segments)} of {len(plan.segments)} segments planned by RRT-Connect "
             f"({plan.timings.get('planning', 0.0):.2f} s)"]  # fmt: skip
    for r in plan.repairs:
        lines.append(f"waypoints[{r.index}] repaired: moved {1000 * r.distance:.1f} mm out of "
                     f"{', '.join(r.obstacles)} to {np.round(r.repaired.position, 3).tolist()}")  # fmt: skip
    if plan.steps:
        secs = np.array([s.seconds for s in plan.steps])
        failed = [s.index for s in plan.steps if s.grasp == "failed"]
        lines.append(f"steps: {len(plan.steps)}, {sum(s.success for s in plan.steps)} verified and collision-free, "
                     f"{100 * plan.kept_share:.0f}% keep the grasp, re-grasps at {plan.regrasps or 'none'}, "
                     f"failed {failed or 'none'}")  # fmt: skip
        lines.append(f"synthesis: {secs.sum():.2f} s, median {np.median(secs):.3f} s a step, "
                     f"p90 {np.percentile(secs, 90):.3f} s")  # fmt: skip
    lines.append(f"total {plan.timings.get('total', 0.0):.2f} s; plan {'succeeded' if plan.success else 'FAILED'}")
    return lines
