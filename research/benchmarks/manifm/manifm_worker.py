"""The ManiFM side of `compare.py`: the release's contact-to-pose optimisation, one case per stdin line.

Runs in the release's own venv (see README.md), never in ours: it imports the release from ``--manifm-src`` (a
work tree of NUS-LinS-Lab/ManiFM) at run time and copies none of its code. Per case it does what the release's
``scripts/pred_w_opt.py`` does after the network, on the caller's contacts instead of the network's:

1. ``PointCloud(points, -normals)`` and ``hand_nb.set_pc`` (the object model),
2. ``define_finger_orders`` + ``generate_icp_poses`` + ``select_best_candidate`` (ICP start for every finger
   permutation, the one whose heat map best overlaps the predicted one),
3. ``hand_nb.contact_wrench_jointpos_opt(fingers, wrench=0.1 * w / |w|, mu=1, step_num=100, step=0.1)`` (the
   iterative SOCP: a force SOCP and a joint-step SOCP per iteration, CVXPY + ECOS, nimblephysics Jacobians).

Steps 1-2 are timed as ``init``, step 3 as ``opt``. The "predicted" heat map that step 2 compares against is the
network's output in the release; here it is built from the given contacts with the release's own
``generate_heatmap_from_tip_pos`` and timed apart (``heatmap``, not part of the case).

Workarounds (README.md): ``pytorch3d`` is replaced by a stub module (the optimisation never calls it; only the
unused ``icp_torch`` and ``ObjectModel`` sampling do), and the thread pool of ``generate_icp_poses`` gets
``--pool-threads`` threads (default 1; the release's ``Pool()`` takes one per core).

Protocol: a JSON case per stdin line -> a JSON record per stdout line; everything else the release or its C++
libraries print goes to stderr.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
import types
import warnings
from pathlib import Path
from typing import Any

import numpy as np

ALLEGRO = "optimization/assets/hands/allegro_hand_right"


def _stub_pytorch3d() -> None:
    """Register a ``pytorch3d`` that raises if called (no CPU wheel; the optimisation path never calls it)."""

    def unavailable(*args: Any, **kwargs: Any) -> Any:
        raise NotImplementedError("pytorch3d is stubbed in this benchmark")

    try:
        import pytorch3d.ops  # noqa: F401
    except ImportError:
        pkg, ops = types.ModuleType("pytorch3d"), types.ModuleType("pytorch3d.ops")
        ops.knn_points = unavailable  # type: ignore[attr-defined]
        ops.sample_farthest_points = unavailable  # type: ignore[attr-defined]
        pkg.ops = ops  # type: ignore[attr-defined]
        sys.modules["pytorch3d"], sys.modules["pytorch3d.ops"] = pkg, ops


class Release:
    """The release's modules and its Allegro hand, loaded once."""

    def __init__(self, src: Path, pool_threads: int) -> None:
        _stub_pytorch3d()
        sys.path.insert(0, str(src))
        from multiprocessing.dummy import Pool

        import pybullet
        import utils.opt_utils as opt_utils
        from optimization import AllegroHand, AllegroHandNb, PointCloud
        from utils.pred_utils import pointcloud_motion_to_wrench

        if pool_threads > 0:
            opt_utils.Pool = lambda *a, **k: Pool(pool_threads)  # type: ignore[assignment]
        self.opt_utils, self.PointCloud, self.motion_to_wrench = opt_utils, PointCloud, pointcloud_motion_to_wrench
        self.hand_nb = AllegroHandNb(
            hand_urdf_path=str(src / ALLEGRO / "allegro_hand_right_nb.urdf"), hand_mesh_path=str(src / ALLEGRO)
        )
        client = pybullet.connect(pybullet.DIRECT)
        pybullet.setGravity(0, 0, 0)
        self.hand = AllegroHand(
            hand_urdf_path=str(src / ALLEGRO / "allegro_hand_right_pb.urdf"), hand_mesh_path=str(src / ALLEGRO),
            physics_client_id=client,
        )  # fmt: skip

    def run(self, case: dict[str, Any]) -> dict[str, Any]:
        """Solve one case; its record (seconds per stage, iterations, flag, residual, final contacts)."""
        ou = self.opt_utils
        points = np.asarray(case["points"], dtype=np.float64)
        normals = np.asarray(case["normals"], dtype=np.float64)
        idx = np.asarray(case["indices"], dtype=np.int64)
        motion = np.tile(np.asarray(case["translation"], dtype=np.float64), (len(points), 1))
        t0 = time.perf_counter()
        heat = ou.generate_heatmap_from_tip_pos(points, [points[i] for i in idx])  # the network's stand-in
        t1 = time.perf_counter()
        pc = self.PointCloud(points, -normals)  # the release wants inward normals (pred_w_opt.build_object_model)
        self.hand_nb.set_pc(pc)
        orders = ou.define_finger_orders(idx)
        candidates = ou.generate_icp_poses(self.hand, self.hand_nb, pc, idx, orders, heat)
        init_pose, fingers = ou.select_best_candidate(candidates)
        t2 = time.perf_counter()
        self.hand_nb.setJoints(init_pose)
        wrench = self.motion_to_wrench(points, motion)
        info = self.hand_nb.contact_wrench_jointpos_opt(
            fingers, wrench=0.1 * wrench / (np.linalg.norm(wrench) + 1e-8), mu=case["mu"], step_num=case["steps"],
            step=0.1,
        )  # fmt: skip
        t3 = time.perf_counter()
        tips = np.array([info["finger_force"][f][0] for f in fingers])
        final = points[[int(pc.kNN(t)[0][0]) for t in tips]]  # the contacts the release ends on (nearest points)
        return {
            "heatmap": t1 - t0, "init": t2 - t1, "opt": t3 - t2, "case": t3 - t1,
            "iterations": int(info["iters"]) + 1,  # update() calls; the release reports the last loop index
            "flag": str(info["flag"]), "success": info["flag"] == "success", "residual": float(info["value"]),
            "fingers": list(fingers), "final_contacts": final.tolist(),
            "tip_distances": [float(self.hand_nb.sign_dist_dict[f]) for f in fingers],
            "joints": np.asarray(info["joints"], dtype=np.float64).tolist(),  # floating base (rotvec, xyz) + 16
            "tips": {f: np.asarray(t).tolist() for f, t in zip(fingers, tips, strict=True)},  # tip link origins
        }  # fmt: skip


def main() -> int:
    """Serve cases on stdin until it closes."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--manifm-src", type=Path, required=True, help="work tree of NUS-LinS-Lab/ManiFM")
    ap.add_argument("--pool-threads", type=int, default=1, help="threads of generate_icp_poses (0: the release's)")
    args = ap.parse_args()
    import torch

    torch.set_num_threads(1)
    warnings.simplefilter("ignore")  # curve_fit on flat faces warns on every projection
    answer = os.fdopen(os.dup(1), "w")
    os.dup2(2, 1)  # nimblephysics and pybullet print from C++: keep stdout for the records
    sys.stdout = sys.stderr
    release = Release(args.manifm_src.resolve(), args.pool_threads)
    answer.write(json.dumps({"ready": True}) + "\n")
    answer.flush()
    for line in sys.stdin:
        if line.strip():
            answer.write(json.dumps(release.run(json.loads(line))) + "\n")
            answer.flush()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
