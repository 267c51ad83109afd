"""Run DexGraspBench's own evaluation on converted answers; runs in DGB's venv, never in ours.

`mani-lab eval dexgraspbench` writes a job (JSON: grasps in DGB's format, see
`research.evaluation.dexgraspbench.convert_answer`) and runs this script with DGB's Python. Per grasp it writes the
``.npy`` DGB reads, builds DGB's configuration with DGB's own Hydra files (``config/base.yaml``, ``task=eval``,
``hand=<hand>``) and calls DGB's evaluation class (``src/task/eval_func/fc_mocap.py`` ``fcMocapEval(path,
configs).run()``, what DGB's ``task_eval`` calls per file), then reads back the result file DGB wrote
(``succ_flag``, ``delta_pos``, ``delta_angle``, ...). No DGB code is copied or changed.

Two things are added around it, both reported and neither changing DGB's logic:

- ``--armature A``: every hand joint's armature set to A (kg·m²) in a copy of DGB's hand XML (``hand.xml_path`` then
  points to it); without it DGB's hands are used as fetched.
- resets: DGB does not look for MuJoCo's divergence warning (mjWARN_BADQACC, after which MuJoCo resets the state
  to the model's initial one). The driver counts those warnings after each of DGB's control steps; a grasp with
  any is reported with ``resets`` > 0 and ``held`` false. (The job places the object away from the origin, so DGB's
  own criterion fails such a grasp too.)

``--fk``: instead of evaluating, write the hand's body positions and joint anchors in its XML world frame for the
given joint values (forward kinematics of DGB's model, for the conversion's checks).

Usage: DGB_PYTHON dgb_driver.py --dgb-dir DGB_SRC --job job.json --out out.json [--armature 0.01] [--fk]
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path
from typing import Any


def _hand_xml(dgb: Path, xml_rel: str, armature: float | None, work: Path) -> str:
    """The hand XML DGB loads: its own, or a copy with every joint's armature set."""
    import mujoco

    path = dgb / xml_rel
    if armature is None:
        return str(path)
    spec = mujoco.MjSpec.from_file(str(path))
    spec.meshdir = str((path.parent / spec.meshdir).resolve())
    for j in spec.joints:
        j.armature = armature
    out = work / f"{path.parent.name}_armature.xml"
    out.write_text(spec.to_xml())
    return str(out)


def _configs(dgb: Path, hand: str, work: Path, xml_path: str) -> Any:
    from hydra import compose, initialize_config_dir

    overrides = [
        "task=eval", f"hand={hand}", "n_worker=1", f"grasp_dir={work}/graspdata", f"eval_dir={work}/evaluation",
        f"succ_dir={work}/succgrasp", f"hand.xml_path={xml_path}",
    ]  # fmt: skip
    with initialize_config_dir(config_dir=str(dgb / "config"), version_base=None):
        return compose(config_name="base", overrides=overrides)


def _qpos(model: Any, root: list[float], joints: dict[str, float]) -> Any:
    """DGB's hand qpos: the root pose, then each hand joint at its address (+7 for the root's free joint)."""
    import numpy as np

    q = np.zeros(7 + model.nq)
    q[:7] = root
    missing = {model.joint(i).name for i in range(model.njnt)} - set(joints)
    if missing:
        raise KeyError(f"no value for DGB joints {sorted(missing)}")
    for name, value in joints.items():
        q[7 + model.jnt_qposadr[model.joint(name).id]] = value
    return q


def evaluate(dgb: Path, job: dict[str, Any], armature: float | None, work: Path) -> list[dict[str, Any]]:
    import mujoco
    import numpy as np

    sys.path.insert(0, str(dgb / "src"))
    os.chdir(dgb)  # DGB's config paths (hand.xml_path) are relative to its root
    from task.eval_func.fc_mocap import fcMocapEval

    results = []
    bad = mujoco.mjtWarning.mjWARN_BADQACC
    for k, g in enumerate(job["grasps"]):
        hand = g["hand"]
        xml = _hand_xml(dgb, f"assets/hand/{hand}/right_hand.xml", armature, work)
        configs = _configs(dgb, hand, work, xml)
        model = mujoco.MjSpec.from_file(xml).compile()
        data = {
            "obj_path": g["obj_path"], "obj_scale": g["obj_scale"], "obj_pose": np.array(g["obj_pose"]),
            **{f"{s}_qpos": _qpos(model, g["root"], g[s]) for s in ("pregrasp", "grasp", "squeeze")},
        }  # fmt: skip
        path = work / "graspdata" / f"{k:05d}.npy"
        path.parent.mkdir(parents=True, exist_ok=True)
        np.save(path, data)
        t0 = time.perf_counter()
        ev = fcMocapEval(str(path), configs)
        step, counted = ev.mj_ho.control_hand_step, {"resets": 0, "last": 0}

        def counting_step(step_inner: int, _step: Any = step, _ev: Any = ev, _c: dict[str, int] = counted) -> None:
            _step(step_inner)
            n = int(_ev.mj_ho.data.warning[bad].number)
            _c["last"] = 0 if n < _c["last"] else _c["last"]  # DGB's reset_pose_qpos cleared the counter
            _c["resets"] += n - _c["last"]
            _c["last"] = n

        ev.mj_ho.control_hand_step = counting_step
        ev.run()
        out = np.load(work / "evaluation" / f"{k:05d}.npy", allow_pickle=True).item()
        succ = bool(out["succ_flag"])
        results.append({
            "id": g["id"], "succ_flag": succ, "held": succ and counted["resets"] == 0, "resets": counted["resets"],
            "delta_pos": float(out["delta_pos"]), "delta_angle": float(out["delta_angle"]),
            "ho_pene": float(out.get("ho_pene", float("nan"))), "seconds": time.perf_counter() - t0,
        })  # fmt: skip
    return results


def forward_kinematics(dgb: Path, job: dict[str, Any]) -> list[dict[str, Any]]:
    import mujoco

    out = []
    for g in job["grasps"]:
        model = mujoco.MjSpec.from_file(str(dgb / f"assets/hand/{g['hand']}/right_hand.xml")).compile()
        data = mujoco.MjData(model)
        data.qpos[:] = _qpos(model, [0.0] * 7, g["grasp"])[7:]
        mujoco.mj_kinematics(model, data)
        mujoco.mj_comPos(model, data)
        out.append({
            "id": g["id"], "bodies": {model.body(i).name: data.xpos[i].tolist() for i in range(model.nbody)},
            "anchors": {model.joint(i).name: data.xanchor[i].tolist() for i in range(model.njnt)},
        })  # fmt: skip
    return out


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--dgb-dir", required=True, help="DexGraspBench's work tree (with its Menagerie hands)")
    p.add_argument("--job", required=True, help="the job JSON ({'grasps': [...]})")
    p.add_argument("--out", required=True, help="where to write the results JSON")
    p.add_argument("--armature", type=float, default=None, help="set every hand joint's armature (kg·m²)")
    p.add_argument("--fk", action="store_true", help="forward kinematics of DGB's hands instead of evaluating")
    args = p.parse_args()
    dgb = Path(args.dgb_dir).resolve()
    job = json.loads(Path(args.job).read_text())
    work = Path(args.out).resolve().parent / (Path(args.out).stem + "_work")
    work.mkdir(parents=True, exist_ok=True)
    import mujoco

    results = forward_kinematics(dgb, job) if args.fk else evaluate(dgb, job, args.armature, work)
    Path(args.out).write_text(json.dumps({"mujoco": mujoco.__version__, "results": results}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
