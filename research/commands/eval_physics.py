"""`mani-lab eval physics`: the service's answers judged by the field's simulated grasp test.

For each hand, the served pipeline (`manifoundation.core.pipeline.run_pipeline`, the path the worker takes; method
``network`` with the worker's default weights is what ``auto`` means without given contacts) answers force closure
on third-party objects (meshes that installed packages ship, `research.audit.third_party_objects`, spread evenly over
the 43 candidates), sent as surface points + normals (``--geometry mesh`` sends the mesh too). Every proposal is then
run through `manifoundation.core.physics` (MuJoCo, DexGraspBench's protocol: six 1 N pushes for 2 s after pregrasp →
grasp → squeeze; holds when the object moves < 5 cm and turns < 15° in all six) on the object's exact mesh.

Columns: proposals, how many the service called verified, how many of those hold, how many of all hold, the median
fingertip gap at the grasp pose (signed distance from each fingertip body's real mesh to the object), the share of
fingertips within 0.5 mm, and how often no finger touches the object after the squeeze; per request, whether its first
proposal holds (the pipeline's order) and whether its best holds once the proposals are ordered by the test
(`manifoundation.core.physics.physics_order`, what ``options.simulate`` returns first): with ``--proposals K`` > 1
the best of K.

The pipeline runs as the service runs it (``options.simulate`` unset): it tests each returned proposal on what it
was sent (the points' patches, or the mesh with ``--geometry mesh``), calls it verified only when it held there and
puts those first. ``--simulate`` asks it to search (``options.simulate: true``): it judges its candidates as it makes
them, draws more until enough hold (`manifoundation.core.pipeline.physics_search`) and returns them ordered by it;
``--no-simulate``: geometric verification only. "first holds" is what the caller gets first; "request s" is the
median pipeline time per request.

``--task lift`` (``delta:0,0,0.05``; any ``delta:x,y,z[,qw,qx,qy,qz]``) asks for that object motion instead and
judges each proposal by the executed target-motion test (`manifoundation.core.physics.simulate_motion`: the same
squeeze, then gravity on and the palm carried along the motion over 1 s, held 0.5 s; reaches when the object ends
within 1 cm and 10° of the target pose); "hold" then means "reached" and three columns add the median final
position / rotation error and how many dropped.

Example:
    mani-lab eval physics --hand leap,allegro,panda_gripper --objects 10 --json physics.json
    mani-lab eval physics --hand leap,allegro,panda_gripper --objects 10 --task lift
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path
from typing import Any

EXIT_OK, EXIT_FAILED, EXIT_USAGE = 0, 1, 2
MODE_TITLE = {None: "checked by the test, ", True: "searched by the test, ", False: ""}
WEIGHTS = Path(__file__).resolve().parents[2] / "manifoundation" / "core" / "weights" / "cpu1k"


def add_physics_parser(sub: Any) -> None:
    """The ``eval physics`` sub-command."""
    a = sub.add_parser("physics", help="third-party objects: the service's answers in the simulated grasp test",
                       description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)  # fmt: skip
    a.add_argument("--hand", default="leap,allegro,panda_gripper", help="hand name(s), comma separated")
    a.add_argument("--objects", type=int, default=10, help="third-party objects, spread over the candidates (≤ 43)")
    a.add_argument("--proposals", type=int, default=1, help="proposals per request (each is simulated)")
    a.add_argument("--points", type=int, default=2048, help="surface points sent")
    a.add_argument("--geometry", choices=("points", "mesh"), default="points", help="what the caller sends")
    a.add_argument("--method", default="network", help="request method (network = auto without contacts)")
    a.add_argument("--weights", default=str(WEIGHTS), help="network weights (method network)")
    a.add_argument("--seed", type=int, default=0)
    a.add_argument("--judge", choices=("mesh", "points"), default="mesh",
                   help="the object the physics test builds: the exact mesh (default) or the sent points' patches")
    a.add_argument("--kp-revolute", type=float, default=None, help="position gain of revolute joints, N·m/rad "
                   "(default: Protocol's 3, MuJoCo Menagerie's LEAP Hand; its Allegro has 10)")
    a.add_argument("--damping-revolute", type=float, default=None, help="revolute joint damping, N·m·s/rad "
                   "(default: Protocol's 0.1; Menagerie's Allegro has 1)")
    a.add_argument("--armature-revolute", type=float, default=None, help="revolute joint armature, kg·m² "
                   "(default: Protocol's 0.01; DexGraspBench's LEAP Hand and Allegro have 0)")
    a.add_argument("--simulate", action=argparse.BooleanOptionalAction, default=None,
                   help="options.simulate: unset, the pipeline tests what it returns (the service's default); "
                   "--simulate, it searches candidates until enough hold (at least 16); --no-simulate, no test")
    a.add_argument("--no-close", action="store_true",
                   help="leave the fingertips where the refinement put them (no closing stage)")
    a.add_argument("--task", default="closure",
                   help="closure (force closure, six pushes), lift (= delta:0,0,0.05) or delta:x,y,z[,qw,qx,qy,qz] "
                   "(the target-motion test)")
    a.add_argument("--json", default=None, help="also write every proposal's record to this file")
    a.set_defaults(func=run_physics)


def parse_task(text: str) -> tuple[list[float], list[float]] | None:
    """``closure`` → None; ``lift`` / ``delta:x,y,z[,qw,qx,qy,qz]`` → (translation (3,), rotation (4,) wxyz).

    Raises:
        ValueError: anything else.
    """
    if text == "closure":
        return None
    text = "delta:0,0,0.05" if text == "lift" else text
    if not text.startswith("delta:"):
        raise ValueError(f"--task {text!r}: closure, lift or delta:x,y,z[,qw,qx,qy,qz]")
    v = [float(x) for x in text.removeprefix("delta:").split(",")]
    if len(v) not in (3, 7):
        raise ValueError(f"--task {text!r}: 3 or 7 numbers")
    return v[:3], v[3:] or [1.0, 0.0, 0.0, 0.0]


def run_physics(args: argparse.Namespace) -> int:
    """Run every (hand, object) and print the table; exit 1 when a proposal called verified fails physics."""
    from dataclasses import replace

    import numpy as np
    import torch
    from rich.console import Console
    from rich.table import Table
    from tqdm import tqdm

    from manifoundation.core import physics as sim
    from manifoundation.core.pipeline import SynthesisInput, TaskInput, physics_mode, run_pipeline
    from manifoundation.core.robots import get_hand
    from research.audit import third_party_objects

    torch.set_num_threads(1)
    try:
        motion = parse_task(args.task)
    except ValueError as exc:
        print(exc)
        return EXIT_USAGE
    task = TaskInput("force_closure")
    if motion is not None:
        task = TaskInput("delta_pose", np.array(motion[0]), np.array(motion[1]))
    protocol = sim.Protocol()
    if args.kp_revolute is not None:
        protocol = replace(protocol, kp_revolute=args.kp_revolute)
    if args.damping_revolute is not None:
        protocol = replace(protocol, damping_revolute=args.damping_revolute)
    if args.armature_revolute is not None:
        protocol = replace(protocol, armature_revolute=args.armature_revolute)
    hands = [h for h in args.hand.split(",") if h]
    every = third_party_objects()
    pick = np.unique(np.linspace(0, len(every) - 1, min(args.objects, len(every))).round().astype(int))
    objects = [every[i] for i in pick]
    predictor = None
    if args.method == "network":
        from manifoundation.core.network import ContactPredictor

        predictor = ContactPredictor.from_checkpoint(args.weights)
    shapes = {
        o.name: sim.from_mesh(o.mesh.vertices, o.mesh.faces) if args.judge == "mesh"
        else sim.from_points(*o.sample(args.points, args.seed))
        for o in objects
    }  # fmt: skip
    records: list[dict[str, Any]] = []
    jobs = [(h, o) for h in hands for o in objects]
    for hand_name, obj in tqdm(jobs, desc="requests"):
        hand = get_hand(hand_name)
        points, normals = obj.sample(args.points, args.seed)
        send = args.geometry == "mesh"
        inp = SynthesisInput(
            points=points, normals=normals, hand=hand, task=task, method=args.method,
            num_proposals=args.proposals, seed=args.seed, hand_key=hand.name, close_gaps=not args.no_close,
            simulate=physics_mode(args.simulate),
            mesh_vertices=np.asarray(obj.mesh.vertices) if send else None,
            mesh_faces=np.asarray(obj.mesh.faces) if send else None,
        )  # fmt: skip
        t0 = time.perf_counter()
        out = run_pipeline(inp, predictor=predictor)
        seconds = time.perf_counter() - t0
        scenes = sim.SceneCache(shapes[obj.name])  # the request's proposals judged in one compiled scene
        for k, p in enumerate(out.proposals):
            assert p.palm_position is not None and p.palm_quaternion is not None and p.joint_values is not None
            grasp = (hand, p.palm_position, p.palm_quaternion, p.joint_values, p.contact_points, p.contact_normals,
                     p.fingertips, shapes[obj.name])  # fmt: skip
            r = (sim.simulate_grasp(*grasp, protocol=protocol, scenes=scenes) if motion is None
                 else sim.simulate_motion(*grasp, np.array(motion[0]), np.array(motion[1]), protocol))  # fmt: skip
            m = r.motion
            records.append({
                "hand": hand_name, "object": obj.name, "proposal": k,
                # what the service calls verified: unless --no-simulate, only what also held in its own test
                "verified": bool(p.quality.success) and (p.physics is None or bool(p.physics.success)),
                "source": p.contact_source, "epsilon": p.quality.epsilon, "holds": r.success, "reason": r.reason,
                "tip_gaps": r.tip_gaps,
                "touching_after_squeeze": r.contacts_after_squeeze, "penetration": r.penetration,
                "trials": [[t.direction, t.translation, t.rotation, t.held] for t in r.trials],
                # unless --no-simulate, the service's own test (on what it was sent) of the same proposal
                "service_trials": None if p.physics is None else [
                    [t.direction, t.translation, t.rotation, t.held] for t in p.physics.trials],
                "motion": None if m is None else [m.translation_error, m.rotation_error, m.dropped],
                "pipeline_s": seconds, "physics_s": r.seconds, "object_pieces": shapes[obj.name].source,
                # the answer as the test ran it (object frame; free joints by name): what `eval dexgraspbench` converts
                "palm_position": p.palm_position.tolist(), "palm_quaternion": p.palm_quaternion.tolist(),
                "joints": list(hand.joint_names), "grasp": p.joint_values.tolist(),
                "pregrasp": r.pregrasp.tolist(), "squeeze": r.squeeze.tolist(),
            })  # fmt: skip
    table = Table(
        title=f"simulated grasp test of the service's answers: {len(objects)} third-party objects, "
        f"{'force closure' if motion is None else 'target motion ' + args.task}, method {args.method}, "
        f"{args.geometry} sent, {args.proposals} proposal(s), "
        f"{'no closing' if args.no_close else 'closed'}, {MODE_TITLE[args.simulate]}"
        f"kp {protocol.kp_revolute:g} N·m/rad, damping {protocol.damping_revolute:g}, "
        f"armature {protocol.armature_revolute:g}, judged on the {args.judge}"
    )
    for col in ("hand", "requests", "first holds", "best holds", "proposals", "verified", "verified & hold", "hold",
                "median tip gap mm", "tips ≤ 0.5 mm", "none touching", "physics s", "request s",
                *(() if motion is None else ("median error mm", "median error deg", "dropped"))):  # fmt: skip
        table.add_column(col, justify="right" if col != "hand" else "left")
    false_claims = 0
    for hand_name in hands:
        rows = [r for r in records if r["hand"] == hand_name]
        gaps = np.array([g for r in rows for g in r["tip_gaps"]])
        ver = [r for r in rows if r["verified"]]
        false_claims += sum(not r["holds"] for r in ver)
        requests: dict[str, list[dict[str, Any]]] = {}
        for rec in rows:
            requests.setdefault(rec["object"], []).append(rec)
        first = sum(rs[0]["holds"] for rs in requests.values())
        best = sum(rs[sim.physics_order([x["verified"] for x in rs], [x["holds"] for x in rs])[0]]["holds"]
                   for rs in requests.values())  # fmt: skip
        table.add_row(
            hand_name, str(len(requests)), f"{first}/{len(requests)}", f"{best}/{len(requests)}", str(len(rows)),
            str(len(ver)), f"{sum(r['holds'] for r in ver)}/{len(ver)}",
            f"{sum(r['holds'] for r in rows)}/{len(rows)}", f"{1000 * np.median(gaps):.1f}" if len(gaps) else "-",
            f"{100 * np.mean(np.abs(gaps) <= 5e-4):.0f} %" if len(gaps) else "-",
            f"{sum(r['touching_after_squeeze'] == 0 for r in rows)}/{len(rows)}",
            f"{np.median([r['physics_s'] for r in rows]):.2f}" if rows else "-",
            f"{np.median([rs[0]['pipeline_s'] for rs in requests.values()]):.2f}" if rows else "-",
            *_motion_cells(rows, motion is None),
        )  # fmt: skip
    Console(width=200).print(table)
    print("objects:", ", ".join(o.name for o in objects))
    if args.json:
        Path(args.json).write_text(json.dumps(records, indent=1))
    return EXIT_FAILED if false_claims else EXIT_OK


def _motion_cells(rows: list[dict[str, Any]], closure: bool) -> tuple[str, ...]:
    """Median final position (mm) and rotation (deg) error and the drops, over the runs that started."""
    import numpy as np

    if closure:
        return ()
    ran = [r["motion"] for r in rows if r["motion"] is not None]
    if not ran:
        return ("-", "-", f"0/{len(rows)}")
    pos = np.median([1000 * min(e[0], 1.0) for e in ran])  # a drop counts as 1 m
    return (f"{pos:.0f}", f"{np.median([e[1] for e in ran]):.1f}", f"{sum(e[2] for e in ran)}/{len(rows)}")
