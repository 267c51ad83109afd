"""`mani-lab eval dexgraspbench`: the answers our physics test judged, judged again by DexGraspBench's own code.

The answers come from a `mani-lab eval physics --json` file (``--json-in``), or that command is run first on
``--hand`` / ``--objects``. Each answer is converted (`research.evaluation.dexgraspbench`: DGB's hand root pose and
joint values for the same pregrasp / grasp / squeeze targets; the object's convex pieces as DGB's object folder) and
evaluated by DGB's ``fcMocapEval`` in DGB's own venv (``research/benchmarks/dexgraspbench/dgb_driver.py``). The
table counts, per hand: answers, held by our test, held by DGB, held by both, disagreements and the difference in
points (DGB − ours), for each ``--armature`` variant: ``fetched`` (DGB's hands as they are) or a value in kg·m² set on
every DGB hand joint (``ours`` = our test's, `manifoundation.core.physics.Protocol.armature_revolute`: 0, as DGB's).
"DGB resets": grasps during which MuJoCo's state diverged and was reset (DGB does not check; counted failed here).

Nothing is downloaded: DGB's work tree and venv are set up once (research/benchmarks/dexgraspbench/README.md) and
named by ``--dgb-dir`` / ``--dgb-python`` (or ``$DGB_SRC`` / ``$DGB_PYTHON``).

Example:
    mani-lab eval physics --hand leap_hand,allegro,shadow --objects 20 --json physics.json
    mani-lab eval dexgraspbench --json-in physics.json --armature fetched,0.01
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import tempfile
from pathlib import Path
from typing import Any

EXIT_OK, EXIT_FAILED, EXIT_USAGE = 0, 1, 2
DRIVER = Path(__file__).resolve().parents[1] / "benchmarks" / "dexgraspbench" / "dgb_driver.py"
SETUP = "research/benchmarks/dexgraspbench/README.md"
MENAGERIE = "third_party/mujoco_menagerie"
NEEDED = ("src/task/eval_func/fc_mocap.py", f"{MENAGERIE}/leap_hand/right_hand.xml",
          f"{MENAGERIE}/wonik_allegro/assets", f"{MENAGERIE}/shadow_hand/assets")  # fmt: skip


def add_dexgraspbench_parser(sub: Any) -> None:
    """The ``eval dexgraspbench`` sub-command."""
    a = sub.add_parser("dexgraspbench", help="the physics test's answers judged by DexGraspBench's own code",
                       description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)  # fmt: skip
    a.add_argument("--json-in", default=None, help="a `mani-lab eval physics --json` file (else it is run first)")
    a.add_argument("--hand", default="leap_hand,allegro,shadow", help="hands (DGB has leap_hand, allegro, shadow)")
    a.add_argument("--objects", type=int, default=20, help="objects: for the physics run, or the first N of --json-in")
    a.add_argument("--dgb-dir", default=os.environ.get("DGB_SRC"), help="DGB's work tree (default $DGB_SRC)")
    a.add_argument("--dgb-python", default=os.environ.get("DGB_PYTHON"),
                   help="the Python of DGB's venv (default $DGB_PYTHON)")  # fmt: skip
    a.add_argument(
        "--armature",
        default="fetched",
        help="comma-separated variants: fetched (DGB's hands as they are), ours (our test's armature) or kg·m²",
    )
    a.add_argument("--workdir", default=None, help="where DGB's files go (default: a temporary folder)")
    a.add_argument("--json", default=None, help="also write every answer's verdicts to this file")
    a.add_argument("--timeout", type=float, default=3600.0, help="seconds per DGB run")
    a.set_defaults(func=run_dexgraspbench)


def setup_problem(dgb_dir: str | None, dgb_python: str | None) -> str | None:
    """Why DGB cannot run (the one-time setup is missing), or None."""
    if not dgb_dir or not dgb_python:
        return "name DGB's work tree and venv Python: --dgb-dir/--dgb-python or $DGB_SRC/$DGB_PYTHON"
    missing = [p for p in NEEDED if not (Path(dgb_dir) / p).exists()]
    if missing:
        return f"{dgb_dir} lacks {', '.join(missing)}"
    if not Path(dgb_python).is_file():
        return f"no Python at {dgb_python}"
    return None


def armatures(text: str) -> list[float | None]:
    """``fetched,ours,0.005`` -> [None, our armature, 0.005].

    Raises:
        ValueError: anything else.
    """
    from manifoundation.core.physics import Protocol

    out: list[float | None] = []
    for v in (x for x in text.split(",") if x):
        out.append(None if v == "fetched" else Protocol().armature_revolute if v == "ours" else float(v))
    return out


def run_dexgraspbench(args: argparse.Namespace) -> int:
    """Convert, run DGB once per armature variant, print the table."""
    problem = setup_problem(args.dgb_dir, args.dgb_python)
    if problem is not None:
        print(f"DexGraspBench is not set up: {problem}.\nOne-time setup (nothing is downloaded at run time): {SETUP}")
        return EXIT_USAGE
    try:
        variants = armatures(args.armature)
    except ValueError as exc:
        print(f"--armature: {exc}")
        return EXIT_USAGE
    work = Path(args.workdir or tempfile.mkdtemp(prefix="dgb-"))
    work.mkdir(parents=True, exist_ok=True)
    hands = [h for h in args.hand.split(",") if h]
    records = _records(args, hands, work)
    if records is None:
        return EXIT_FAILED
    jobs = _convert(records, work)
    if not jobs:
        print("no answer for a hand DGB has")
        return EXIT_FAILED
    fk = _fk_agreement(args, jobs, records, work)
    if fk is None:
        return EXIT_FAILED
    verdicts: list[dict[str, Any]] = []
    for arm in variants:
        name = "fetched" if arm is None else f"armature {arm:g}"
        out = work / f"dgb_{'fetched' if arm is None else f'arm{arm:g}'}.json"
        cmd = [args.dgb_python, str(DRIVER), "--dgb-dir", args.dgb_dir, "--job", str(work / "job.json"), "--out",
               str(out), *([] if arm is None else ["--armature", str(arm)])]  # fmt: skip
        print(f"DGB ({name}): {len(jobs)} answers ...", flush=True)
        done = subprocess.run(cmd, capture_output=True, text=True, timeout=args.timeout)
        if done.returncode != 0:
            print(f"DGB's run failed ({done.returncode}):\n{done.stderr[-3000:]}")
            return EXIT_FAILED
        for res in json.loads(out.read_text())["results"]:
            verdicts.append({**res, "variant": name, "fk_mm": fk[res["id"]], **records[res["id"]]})
    _table(verdicts)
    if args.json:
        Path(args.json).write_text(json.dumps(verdicts, indent=1))
    return EXIT_OK


def _records(args: argparse.Namespace, hands: list[str], work: Path) -> list[dict[str, Any]] | None:
    """The physics test's records (read, or made by running `eval physics`), limited to ``hands`` and the first
    ``--objects`` objects, each with an ``id``."""
    path = args.json_in
    if path is None:
        from research.commands.eval_physics import run_physics

        path = str(work / "physics.json")
        ns = argparse.Namespace(
            hand=",".join(hands), objects=args.objects, proposals=1, points=2048, geometry="points", method="network",
            weights=None, seed=0, judge="mesh", kp_revolute=None, damping_revolute=None, armature_revolute=None,
            simulate=None, no_close=False, task="closure", json=path,
        )  # fmt: skip
        from research.commands.eval_physics import WEIGHTS

        ns.weights = str(WEIGHTS)
        run_physics(ns)
    rows = [r for r in json.loads(Path(path).read_text()) if r["hand"] in hands]
    if rows and "palm_position" not in rows[0]:
        print(f"{path} has no answers to convert: re-run `mani-lab eval physics --json` (records since issue 63)")
        return None
    keep: list[str] = []
    for r in rows:
        if r["object"] not in keep and len(keep) < args.objects:
            keep.append(r["object"])
    rows = [r for r in rows if r["object"] in keep and r["motion"] is None]
    return [{**r, "id": i} for i, r in enumerate(rows)]


def _convert(records: list[dict[str, Any]], work: Path) -> list[dict[str, Any]]:
    """Write DGB's objects and the job file; the job's grasps."""
    from manifoundation.core import physics as sim
    from manifoundation.core.robots import get_hand
    from research.audit import third_party_objects
    from research.evaluation.dexgraspbench import HANDS, convert_answer, write_object

    objects = {o.name: o for o in third_party_objects()}
    centres = {}
    grasps = []
    for r in records:
        if r["hand"] not in HANDS or r["object_pieces"] not in ("hull", "mesh_patches"):
            continue  # no DGB counterpart, or judged on the sent points (eval physics --judge points)
        folder = work / "objects" / r["object"]
        if r["object"] not in centres:
            o = objects[r["object"]]
            centres[r["object"]] = write_object(sim.from_mesh(o.mesh.vertices, o.mesh.faces), folder)
        g = convert_answer(get_hand(r["hand"]), r, centres[r["object"]], folder)
        grasps.append({**g, "id": r["id"], "hand": HANDS[r["hand"]].config})
    (work / "job.json").write_text(json.dumps({"grasps": grasps}))
    return grasps


def _fk_agreement(
    args: argparse.Namespace, jobs: list[dict[str, Any]], records: list[dict[str, Any]], work: Path
) -> dict[int, float] | None:
    """Answer id -> largest distance (mm) between our bodies and DGB's after the conversion (`dexgraspbench_fk`)."""
    import numpy as np

    from manifoundation.core.robots import get_hand
    from research.evaluation.dexgraspbench_fk import dgb_bodies, max_distance, our_bodies

    out = work / "dgb_fk.json"
    cmd = [args.dgb_python, str(DRIVER), "--dgb-dir", args.dgb_dir, "--job", str(work / "job.json"), "--out",
           str(out), "--fk"]  # fmt: skip
    done = subprocess.run(cmd, capture_output=True, text=True, timeout=args.timeout)
    if done.returncode != 0:
        print(f"DGB's forward kinematics failed ({done.returncode}):\n{done.stderr[-3000:]}")
        return None
    theirs = {r["id"]: r["bodies"] for r in json.loads(out.read_text())["results"]}
    fk = {}
    for g in jobs:
        r = records[g["id"]]
        hand = get_hand(r["hand"])
        palm = np.asarray(r["palm_position"]) + np.asarray(g["shift"])
        ours = our_bodies(hand, palm, np.asarray(r["palm_quaternion"]), np.asarray(r["grasp"]))
        fk[g["id"]] = 1000 * max_distance(ours, dgb_bodies(r["hand"], np.asarray(g["root"]), theirs[g["id"]]))
    return fk


def _table(verdicts: list[dict[str, Any]]) -> None:
    from rich.console import Console
    from rich.table import Table

    table = Table(title="our physics test vs DexGraspBench's evaluation (fcMocapEval) on the same answers")
    for col in ("hand", "DGB hands", "answers", "held: ours", "held: DGB", "both", "disagree", "DGB − ours",
                "DGB resets", "FK max mm"):  # fmt: skip
        table.add_column(col, justify="left" if col in ("hand", "DGB hands") else "right")
    for name in dict.fromkeys(v["variant"] for v in verdicts):
        for hand in dict.fromkeys(v["hand"] for v in verdicts):
            rows = [v for v in verdicts if v["variant"] == name and v["hand"] == hand]
            n = len(rows)
            ours, dgb = sum(v["holds"] for v in rows), sum(v["held"] for v in rows)
            both = sum(v["holds"] and v["held"] for v in rows)
            table.add_row(
                hand, name, str(n), f"{ours} ({100 * ours / n:.0f} %)", f"{dgb} ({100 * dgb / n:.0f} %)", str(both),
                str(sum(v["holds"] != v["held"] for v in rows)), f"{100 * (dgb - ours) / n:+.0f}",
                str(sum(v["resets"] > 0 for v in rows)), f"{max(v['fk_mm'] for v in rows):.2g}",
            )  # fmt: skip
    Console(width=160).print(table)
