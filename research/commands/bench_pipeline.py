"""`mani-lab bench pipeline`: one request through `run_pipeline`, per stage, per hand, and beside a reference checkout.

Each request (a built-in hand, an object, a task, ``--proposals`` proposals, one thread) runs in a worker process;
the time of every stage is recorded — prepare (field, mass), network, initialisation, refinement (split into the
linearisation, of which the contact model on the real surfaces and its object-point guards, and the SCP solve),
verification — with the iterations, the verified proposals and, with ``--audit N``, the outside audit
(`research.audit`) of the first N requests' proposals of each hand. The table gives p50/p90 latency and verified
grasps per second (one core, requests one after the other).

``--compare REF`` runs the same requests through a second checkout (``git worktree add /tmp/ref main``) in its own
worker process (``PYTHONPATH=REF``, same interpreter), interleaved request by request (A B A B: both see the same
machine load), and prints both, the ratios, and how many answers are identical (same success, joints and palm
within 1e-9). Both workers run this file as a script, so the reference needs no copy of it. ``--compare-method
M`` does the same with this checkout and another method: ``--method network --compare-method random_contacts``
is the network's starts against random ones on the same requests (``--weights`` picks the network).

Objects: ``third_party`` (the audit's meshes that installed packages ship, `research.audit.third_party_objects`; there
are 43, the first 18 the original set; ``--seeds`` repeats each with other samples and contacts; each spec names its
file, so a reference checkout with fewer candidates loads the same objects), ``procedural``
(`manifoundation.core.objects`), or ``box`` (``examples/data/box.npz``, no mesh: the README protocol). ``--order
object`` asks each object of every hand in a row (the second hand's request finds the first's object in the worker's
object cache, `manifoundation.core.pipeline.object_cache`), instead of each hand's requests in turn.

Example:
    mani-lab bench pipeline --hand leap,allegro --set third_party --seeds 3 --audit 6 --compare /tmp/ref-23
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

EXIT_OK = 0
ROOT = Path(__file__).resolve().parents[2]
STAGES = ("prepare", "network", "initialisation", "refinement", "verification")
PARTS = ("linearise", "contacts", "guards", "solve")
"""Refinement parts timed by wrapping the functions of these names (contacts, guards ⊂ linearise)."""


def register(subparsers: Any) -> None:
    """Add ``pipeline`` to the ``mani-lab bench`` sub-commands."""
    p = subparsers.add_parser("pipeline", help="one request per stage, p50/p90, verified grasps/s (vs a reference)",
                              description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    add_arguments(p)
    p.set_defaults(func=run)


def add_arguments(p: argparse.ArgumentParser) -> None:
    """The command's options (shared with `main`)."""
    p.add_argument("--hand", default="leap,allegro", help="hand names, comma separated, or 'all'")
    p.add_argument("--set", default="third_party", choices=("third_party", "procedural", "box"))
    p.add_argument("--objects", type=int, default=18, help="objects of the set (third_party: at most 43)")
    p.add_argument("--seeds", type=int, default=3, help="requests per object (seeds 0..N-1)")
    p.add_argument("--order", default="hand", choices=("hand", "object"),
                   help="hand: each hand's requests in turn (an object's seeds in a row); object: each object's "
                        "requests for every hand in a row (an object sent again, as a planner or a batch of one "
                        "object's tasks does)")
    p.add_argument("--task", default="lift", choices=("lift", "closure"))
    p.add_argument("--geometry", default="mesh", choices=("mesh", "points"), help="send the mesh or points only")
    p.add_argument("--proposals", type=int, default=1)
    p.add_argument("--method", default="random_contacts")
    p.add_argument("--points", type=int, default=2048, help="surface points sent (third_party)")
    p.add_argument("--audit", type=int, default=0, help="audit the proposals of the first N requests per hand")
    p.add_argument("--compare", default=None, help="a reference checkout's root, run side by side")
    p.add_argument("--compare-method", default=None,
                   help="run the same requests through this checkout with this method too, side by side (e.g. "
                        "--method network --compare-method random_contacts)")
    p.add_argument("--simulate", default="off", choices=("off", "check", "search"),
                   help="the simulated grasp test (`PhysicsMode`; the service's default is check: each returned "
                   "proposal tested, verified only if it held; off: geometric only)")
    p.add_argument("--compare-simulate", default=None, choices=("off", "check", "search"),
                   help="run the same requests through this checkout with this physics mode too, side by side "
                   "(e.g. --simulate check --compare-simulate off)")
    p.add_argument(
        "--weights", default=str(ROOT / "manifoundation/core/weights/cpu1k"), help="network weights (method network)"
    )
    p.add_argument("--json", default=None, help="also write every request's record here")
    p.add_argument("--workers", type=int, default=1,
                   help="N > 1: the batch mode, every request through N worker processes at once (one thread "
                        "each), each checkout in turn, twice (A B B A); prints verified grasps/s of the wall time "
                        "(the objects are read and sampled before the clock starts; an audited request counts its "
                        "audit: use --audit 0 for throughput)")


def requests(args: argparse.Namespace) -> list[dict[str, Any]]:
    """The request specs, hand-major or (``--order object``) object-major (a worker rebuilds each request from its
    spec; the audit marks are given hand-major either way)."""
    from manifoundation.core.robots import list_hands

    hands = list(list_hands()) if args.hand == "all" else [h for h in args.hand.split(",") if h]
    count = 1 if args.set == "box" else args.objects
    files: list[tuple[str, str]] = []
    if args.set == "third_party":
        from research.audit import third_party_objects

        files = [(o.name, str(o.path)) for o in third_party_objects(count)]
        count = min(count, len(files))
    out = []
    for hand in hands:
        n = 0
        for obj in range(count):
            for seed in range(args.seeds):
                name, path = files[obj] if files else ("", "")
                out.append({"hand": hand, "set": args.set, "object": obj, "name": name, "path": path,
                            "seed": seed, "task": args.task,
                            "geometry": args.geometry, "proposals": args.proposals, "method": args.method,
                            "simulate": args.simulate,
                            "weights": str(Path(args.weights).resolve()),
                            "points": args.points, "audit": n < args.audit and args.set != "box",
                            "box": str(ROOT / "examples/data/box.npz")})
                n += 1
    if getattr(args, "order", "hand") == "object":
        out.sort(key=lambda spec: (spec["object"], spec["seed"]))  # stable: the hands in their order
    return out


def run(args: argparse.Namespace) -> int:
    """Run every request in the worker(s), interleaved, and print the tables."""
    specs = requests(args)
    trees = {"current": str(ROOT)}
    changes: dict[str, dict[str, Any]] = {"current": {}}
    if args.compare:
        trees["reference"] = str(Path(args.compare).resolve())
        changes["reference"] = {}
    if args.compare_method:
        trees[args.compare_method] = str(ROOT)
        changes[args.compare_method] = {"method": args.compare_method}
    if args.compare_simulate:
        trees[f"simulate {args.compare_simulate}"] = str(ROOT)
        changes[f"simulate {args.compare_simulate}"] = {"simulate": args.compare_simulate}
    if args.workers > 1:
        return _batch(args, specs, trees, changes)
    workers = {name: _Worker(tree, changes[name]) for name, tree in trees.items()}
    records: dict[str, list[dict[str, Any]]] = {name: [] for name in trees}
    try:
        from tqdm import tqdm

        first = {s["hand"]: s for s in reversed(specs)}  # each hand's first request
        for w in workers.values():  # warm-up, not recorded: imports, each hand's caches, the objects
            for spec in first.values():
                w.ask(dict(spec, audit=False))

        for i, spec in enumerate(tqdm(specs, desc="requests")):
            order = list(workers) if i % 2 == 0 else list(reversed(workers))  # A B, then B A
            for name in order:
                records[name].append(workers[name].ask(spec))
    finally:
        for w in workers.values():
            w.close()
    if args.json:
        Path(args.json).write_text(json.dumps({"specs": specs, "records": records}))
    from research.commands.bench_pipeline_report import print_report

    print_report(specs, records, load=os.getloadavg())
    return EXIT_OK


def _batch(args: argparse.Namespace, specs: list[dict[str, Any]], trees: dict[str, str],
           changes: dict[str, dict[str, Any]]) -> int:  # fmt: skip
    """The batch mode: each checkout's N workers take the requests from one queue; checkouts in turn, twice (A B,
    then B A: on this machine the first round of a run was 5-20 % slower whichever checkout ran it)."""
    from rich.console import Console

    console = Console(width=200)
    rounds: dict[str, list[tuple[float, list[dict[str, Any]]]]] = {name: [] for name in trees}
    for order in (list(trees), list(reversed(trees))):  # A B, then B A: a machine that drifts favours neither
        for name in order:
            rounds[name].append(_pool_run(trees[name], specs, args.workers, changes[name]))
    load = os.getloadavg()
    for name, runs in rounds.items():
        for k, (wall, recs) in enumerate(runs):
            verified = sum(sum(r["success"]) for r in recs)
            audited = [r for r in recs if r["audit"] is not None]
            passed = sum(bool(r["audit"][0]) for r in audited)
            false = sum(c and not a for r in audited for c, a in zip(r["success"], r["audit"], strict=True))
            console.print(f"{name} round {k + 1}: {len(recs)} requests on {args.workers} workers in {wall:.1f} s: "
                          f"{len(recs) / wall:.2f} requests/s, {verified / wall:.2f} verified grasps/s "
                          f"({verified} verified); audit {passed}/{len(audited)} best proposals, {false} false "
                          f"claims")  # fmt: skip
    console.print(f"load average at the end (1, 5, 15 min): {load[0]:.2f} {load[1]:.2f} {load[2]:.2f}")
    if args.json:
        Path(args.json).write_text(json.dumps({"specs": specs, "rounds": rounds}))
    return EXIT_OK


def _pool_run(tree: str, specs: list[dict[str, Any]], count: int,
              change: dict[str, Any]) -> tuple[float, list[dict[str, Any]]]:  # fmt: skip
    """Every spec through ``count`` workers of ``tree`` (each takes the next request when done): wall seconds
    (warm-up and the objects' loading excluded) and the records in spec order."""
    import queue
    from concurrent.futures import ThreadPoolExecutor

    pool = [_Worker(tree, change) for _ in range(count)]
    free: queue.Queue[_Worker] = queue.Queue()
    first = [dict(s, audit=False) for s in {s["hand"]: s for s in reversed(specs)}.values()]

    def one(spec: dict[str, Any]) -> dict[str, Any]:
        worker = free.get()
        try:
            return worker.ask(spec)
        finally:
            free.put(worker)

    try:
        for w in pool:
            free.put(w)
        # warm-up, not timed: each worker's imports and hands, and every object read from its file and sampled
        # (a service receives the points in the request; reading and sampling a mesh file, 15 ms, is the bench's)
        loads = [dict(s, load_only=True) for s in specs]
        with ThreadPoolExecutor(count) as ex:
            list(ex.map(lambda w: [w.ask(s) for s in first + loads], pool))
        t0 = time.perf_counter()
        with ThreadPoolExecutor(count) as ex:
            records = list(ex.map(one, specs))
        return time.perf_counter() - t0, records
    finally:
        for w in pool:
            w.close()


class _Worker:
    """A worker process running this file against one checkout (``PYTHONPATH=tree``), one request per line;
    ``change`` replaces fields of every spec it is asked (another method)."""

    def __init__(self, tree: str, change: dict[str, Any] | None = None) -> None:
        self.change = dict(change or {})
        env = dict(os.environ, PYTHONPATH=tree, OMP_NUM_THREADS="1", MKL_NUM_THREADS="1")
        self.proc = subprocess.Popen([sys.executable, str(Path(__file__).resolve()), "--worker"], env=env,
                                     stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True, cwd=tree)

    def ask(self, spec: dict[str, Any]) -> dict[str, Any]:
        assert self.proc.stdin is not None and self.proc.stdout is not None
        self.proc.stdin.write(json.dumps(dict(spec, **self.change)) + "\n")
        self.proc.stdin.flush()
        line = self.proc.stdout.readline()
        if not line:
            raise RuntimeError(f"bench worker exited ({self.proc.wait()})")
        return dict(json.loads(line))

    def close(self) -> None:
        if self.proc.stdin is not None:
            self.proc.stdin.close()
        self.proc.wait(timeout=60)


def main(argv: list[str] | None = None) -> int:
    """Run the command without the ``mani`` entry point (``python -m research.commands.bench_pipeline ...``)."""
    p = argparse.ArgumentParser(prog="mani-lab bench pipeline", description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    add_arguments(p)
    return run(p.parse_args(argv))


if __name__ == "__main__":
    if sys.argv[1:] == ["--worker"]:  # run as a script: import ``models`` from PYTHONPATH, never this directory
        import importlib.util

        here = Path(__file__).resolve().parent
        sys.path[:] = [p for p in sys.path if Path(p or ".").resolve() != here]
        spec = importlib.util.spec_from_file_location("bench_pipeline_worker", here / "bench_pipeline_worker.py")
        assert spec is not None and spec.loader is not None
        worker = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(worker)
        raise SystemExit(worker.serve())
    raise SystemExit(main())
