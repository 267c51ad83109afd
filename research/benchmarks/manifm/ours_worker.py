"""Our side of `compare.py`: ``run_pipeline`` with method "contacts", one case per stdin line.

Runs with our venv and ``PYTHONPATH`` at the checkout. The case's contacts go in as the caller's contacts; the
pipeline picks the finger assignment and start (``initialisation``), refines (``refinement``, the SOCP loop) and
verifies (``verification``). ``init`` is prepare + initialisation, ``opt`` is refinement, ``case`` is the whole
``run_pipeline`` call (verification included).

Protocol: a JSON case per stdin line -> a JSON record per stdout line; anything else printed goes to stderr.
"""

from __future__ import annotations

import json
import os
import sys
import time
from typing import Any

import numpy as np

TIP_LINKS = {"index": "link_3.0_tip", "middle": "link_7.0_tip", "ring": "link_11.0_tip", "thumb": "link_15.0_tip"}
"""The release's finger names -> the Allegro tip links (the same link names in its URDF and ours)."""


def _request(case: dict[str, Any], hand: Any) -> Any:
    from manifoundation.core.pipeline import SynthesisInput, TaskInput

    task = TaskInput("delta_pose", translation=np.asarray(case["translation"], dtype=np.float64),
                     rotation=np.array([1.0, 0.0, 0.0, 0.0]))  # fmt: skip
    return SynthesisInput(
        points=np.asarray(case["points"], dtype=np.float64), normals=np.asarray(case["normals"], dtype=np.float64),
        hand=hand, task=task, method="contacts", contacts=np.asarray(case["contacts"], dtype=np.float64),
        properties={"friction": float(case["mu"])}, max_iterations=int(case["steps"]), seed=int(case["seed"]),
    )  # fmt: skip


def release_pose(joints: list[float]) -> Any:
    """The release's final Allegro pose as our `HandPose`: its floating base (rotation vector, position) times
    its fixed ``floating_to_palm`` joint (xyz 0 0.02 -0.015, rpy -pi/2 -pi/2 0) is our palm frame ``palm_link``;
    its DoF order index, thumb, middle, ring -> ours joint_0.0 .. joint_15.0 (index, middle, ring, thumb)."""
    from scipy.spatial.transform import Rotation

    from manifoundation.core.refine.state import HandPose

    q = np.asarray(joints, dtype=np.float64)
    base = Rotation.from_rotvec(q[:3])
    palm = base * Rotation.from_euler("xyz", [-np.pi / 2, -np.pi / 2, 0.0])
    pos = q[3:6] + base.apply([0.0, 0.02, -0.015])
    x, y, z, w = palm.as_quat()
    fingers = np.concatenate([q[6:10], q[14:18], q[18:22], q[10:14]])
    return HandPose(pos, np.array([w, x, y, z]), fingers)


def check(case: dict[str, Any], hand: Any) -> dict[str, Any]:
    """Our verification of the release's final pose (untimed): success, failures, and how far our tip links are
    from the release's for the same joint values (its distal tip links are 2 mm longer)."""
    from manifoundation.core.pipeline.prepare import prepare
    from manifoundation.core.refine.verify import verify

    pose = release_pose(case["joints"])
    prep = prepare(_request(case, hand))
    ver = verify(hand, pose, prep.cloud, prep.task, prep.mu, prep.mesh)
    links = hand.link_poses(*pose.tensors())
    gap = [
        float(np.linalg.norm(links[TIP_LINKS[f]][0, :3, 3].numpy() - np.asarray(t))) for f, t in case["tips"].items()
    ]
    return {"success": bool(ver.success), "failures": list(ver.failures), "tip_link_gap_max": max(gap),
            "max_tip_distance": float(ver.max_tip_distance), "penetration": float(ver.penetration)}  # fmt: skip


def run(case: dict[str, Any], hand: Any) -> dict[str, Any]:
    """Solve one case; its record (seconds per stage, iterations, success, residual, final contacts)."""
    from manifoundation.core.pipeline import run_pipeline

    if "joints" in case:
        return check(case, hand)
    inp = _request(case, hand)
    t0 = time.perf_counter()
    out = run_pipeline(inp)
    wall = time.perf_counter() - t0
    p, s = out.proposals[0], out.timings
    q = p.quality
    return {
        "init": s.get("prepare", 0.0) + s.get("initialisation", 0.0), "opt": s.get("refinement", 0.0),
        "verify": s.get("verification", 0.0), "case": wall, "iterations": int(q.iterations),
        "flag": q.reason, "success": bool(q.success), "residual": float(q.wrench_residual),
        "max_tip_distance": float(q.max_tip_distance), "penetration": float(q.penetration_depth),
        "failures": list(q.failures),
        "fingers": list(p.fingertips), "final_contacts": np.asarray(p.contact_points).tolist(),
    }  # fmt: skip


def main() -> int:
    """Serve cases on stdin until it closes."""
    import torch

    from manifoundation.core.robots import get_hand

    torch.set_num_threads(1)
    answer = os.fdopen(os.dup(1), "w")
    os.dup2(2, 1)
    sys.stdout = sys.stderr
    hand = get_hand(sys.argv[1] if len(sys.argv) > 1 else "allegro")
    answer.write(json.dumps({"ready": True}) + "\n")
    answer.flush()
    for line in sys.stdin:
        if line.strip():
            answer.write(json.dumps(run(json.loads(line), hand)) + "\n")
            answer.flush()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
