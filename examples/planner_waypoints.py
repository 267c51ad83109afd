"""Put the cup in the box: hand-written waypoints (the kind an LLM task planner proposes), one of them in
collision, turned into a collision-free trajectory with a grasp at every step — locally with the science, or
through the service (``--url``: ``POST /v1/plans`` with the SDK's ``Client.plan``).

The scene: a table, a cup standing on it, a kettle-sized block in the way, and an open box. The planner says
"lift the cup, carry it past the kettle, hold it above the box, lower it in"; its second waypoint puts the cup
inside the kettle. `plan_manipulation` moves that waypoint to the nearest free position, plans each segment with
RRT-Connect, densifies the path and synthesises contacts for every step, keeping the grasp while it works and
re-grasping where it must. Every step's answer is verified like a single synthesis request, and its hand is
checked against the scene.

    .venv/bin/python examples/planner_waypoints.py --hand allegro --html cup_in_box.html
    .venv/bin/python examples/planner_waypoints.py --write-plan out/   # then: mani plan out/plan.yaml
    .venv/bin/python examples/planner_waypoints.py --url http://127.0.0.1:8000   # against `mani serve`

Through the service the answer is the same plan (the worker runs the same `plan_manipulation`); the job's page
(``/view/<job id>``, printed) plays it: the scene, the cup along its path, the hand and contacts at every step.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np


def cup_in_box_request(hand_name: str, method: str, seed: int):  # -> manifoundation.core.planning.PlanInput
    """The example's plan request."""
    from manifoundation.core.planning import BoxObstacle, PlanInput, PlanOptions, Pose, SupportPlane
    from manifoundation.core.planning.scenes import cup_mesh, open_box, sampled
    from manifoundation.core.robots import get_hand

    cup = cup_mesh()
    points, normals = sampled(cup, 1024, seed=0)
    kettle = BoxObstacle(np.array([0.12, 0.12, 0.20]), Pose(np.array([0.02, 0.0, 0.10])), "kettle")
    box = open_box(np.array([-0.22, 0.18]), np.array([0.24, 0.24, 0.06]), name="box")
    waypoints = [
        Pose(np.array([0.25, -0.15, 0.12])),  # lift the cup
        Pose(np.array([0.02, 0.0, 0.16])),  # "carry it over the kettle": inside the kettle (the planner's mistake)
        Pose(np.array([-0.22, 0.18, 0.16])),  # above the box
        Pose(np.array([-0.22, 0.18, 0.012])),  # lowered in, 2 mm above the box floor
    ]
    return PlanInput(
        points=points, normals=normals, hand=get_hand(hand_name),
        start=Pose(np.array([0.25, -0.15, 0.0])),  # standing on the table
        waypoints=waypoints, obstacles=[kettle, *box], support=SupportPlane(0.0),
        mesh_vertices=np.asarray(cup.vertices), mesh_faces=np.asarray(cup.faces), properties={"friction": 0.8},
        options=PlanOptions(time_limit=5.0, translation_step=0.03, rotation_step=0.25, seed=seed, method=method),
        hand_key=hand_name,
    )  # fmt: skip


def write_plan_file(inp, folder: Path) -> Path:  # inp: manifoundation.core.planning.PlanInput
    """The request as a plan file for ``mani plan`` (the cup saved beside it as an .npz)."""
    import yaml

    from manifoundation.core.planning import BoxObstacle
    from manifoundation.core.planning.export import pose_dict

    folder.mkdir(parents=True, exist_ok=True)
    np.savez(folder / "cup.npz", points=inp.points, normals=inp.normals, vertices=inp.mesh_vertices,
             faces=inp.mesh_faces)  # fmt: skip
    obstacles = [{"kind": "box", "name": o.name, "size": np.asarray(o.size).tolist(), "pose": pose_dict(o.pose)}
                 for o in inp.obstacles if isinstance(o, BoxObstacle)]  # fmt: skip
    opt = inp.options
    plan = {
        "object": {"file": "cup.npz", "properties": dict(inp.properties)},
        "robot": {"name": inp.hand.name},
        "start": pose_dict(inp.start),
        "waypoints": [pose_dict(w) for w in inp.waypoints],
        "scene": {"support_plane": {"height": inp.support.height}, "obstacles": obstacles},
        "options": {"time_limit": opt.time_limit, "translation_step": opt.translation_step,
                    "rotation_step": opt.rotation_step, "seed": opt.seed, "method": opt.method},
    }  # fmt: skip
    path = folder / "plan.yaml"
    path.write_text(yaml.safe_dump(plan, sort_keys=False))
    return path


def wire_request(inp):  # inp: manifoundation.core.planning.PlanInput -> manifoundation.contract.PlanRequest
    """The same request in the wire contract's terms (what ``POST /v1/plans`` and the MCP tool take)."""
    from manifoundation.sdk import box_obstacle, make_plan, object_from_points

    obj = object_from_points(inp.points, inp.normals, mesh={"vertices": inp.mesh_vertices, "faces": inp.mesh_faces},
                             properties=dict(inp.properties))  # fmt: skip
    obstacles = [box_obstacle(o.size, o.pose.position, o.pose.quaternion, name=o.name) for o in inp.obstacles]
    opt = inp.options
    return make_plan(
        obj, [*inp.start.position, *inp.start.quaternion], [[*w.position, *w.quaternion] for w in inp.waypoints],
        inp.hand.name, obstacles=obstacles, support_plane=inp.support.height, time_limit=opt.time_limit,
        translation_step=opt.translation_step, rotation_step=opt.rotation_step, seed=opt.seed, method=opt.method,
    )  # fmt: skip


def through_the_service(inp, url: str, api_key: str | None) -> int:  # inp: manifoundation.core.planning.PlanInput
    """Plan with ``POST /v1/plans`` (the SDK), following the job's stages; print what the local run prints."""
    import time

    from manifoundation.sdk import Client

    with Client(url, api_key) as client:
        t0 = time.perf_counter()
        job = client.submit_plan(wire_request(inp))
        print(f"job {job.id}: {url}/view/{job.id}")
        last = None
        while not (status := job.status()).state.terminal:
            p = status.progress
            now = (p.stage.value, p.completed, p.total)
            if now != last and p.total:
                print(f"  {p.stage.value}: {p.completed}/{p.total}")
                last = now
            time.sleep(0.2)
        plan = job.plan_result(5)
    repaired = ", ".join(f"waypoints[{r.index}] moved {1000 * r.distance:.1f} mm out of {', '.join(r.obstacles)}"
                         for r in plan.repairs) or "none"  # fmt: skip
    print(f"trajectory: {len(plan.positions)} poses; repairs: {repaired}")
    print(f"steps: {len(plan.steps)}, {sum(s.success for s in plan.steps)} verified and collision-free, "
          f"{100 * plan.kept_share:.0f}% keep the grasp, re-grasps at {plan.regrasps or 'none'}")  # fmt: skip
    print(f"{time.perf_counter() - t0:.1f} s through the service; plan {'succeeded' if plan.success else 'FAILED'}")
    return 0 if plan.success else 1


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--hand", default="allegro")
    parser.add_argument("--method", default="random_contacts", choices=("random_contacts", "network"))
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--html", type=Path, default=None, help="write a 3D view that plays the plan")
    parser.add_argument("--write-plan", type=Path, default=None, help="also write the request as a plan file here")
    parser.add_argument("--url", default=None, help="plan through this service (POST /v1/plans) instead of locally")
    parser.add_argument("--api-key", default=None, help="the service's API key, when it has keys")
    args = parser.parse_args()

    import torch

    from manifoundation.core.planning import plan_manipulation, scene_of
    from manifoundation.core.planning.export import summary_lines

    torch.set_num_threads(1)
    inp = cup_in_box_request(args.hand, args.method, args.seed)
    if args.write_plan:
        print(f"plan file: {write_plan_file(inp, args.write_plan)}")
    if args.url:
        return through_the_service(inp, args.url, args.api_key)
    predictor = None
    if args.method == "network":
        from manifoundation.server.commands.plan import load_predictor

        predictor = load_predictor(None)
    plan = plan_manipulation(inp, predictor)
    for line in summary_lines(plan):
        print(line)
    for step in plan.steps:
        if step.grasp != "kept":
            q = step.proposal.quality if step.proposal is not None else None
            print(f"  step {step.index:3d}: {step.grasp:8s} {step.seconds:6.2f} s, {step.calls} synthesis call(s), "
                  f"verified {q.success if q else False}, hand meets {step.hand_collisions or 'nothing'}"
                  + (f" (previous grasp dropped: {step.dropped})" if step.dropped else ""))
    if args.html:
        from manifoundation.core.planning.view import plan_figure

        plan_figure(plan, scene_of(inp), inp.hand).write_html(str(args.html), include_plotlyjs=True)
        print(f"view: {args.html}")
    return 0 if plan.success else 1


if __name__ == "__main__":
    raise SystemExit(main())
