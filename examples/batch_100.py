"""A batch of 100 requests (5 objects x 4 tasks x 5 seeds) with a progress bar; results in request order.

    .venv/bin/python examples/batch_100.py --out results.jsonl

The requests go in one ``POST /v1/batches`` (up to 1000 per batch); ``as_completed`` yields each item as its
job finishes, and ``wait``/``results`` give them back in request order.
"""

from __future__ import annotations

import argparse
import itertools
import json
import os
from collections import Counter
from pathlib import Path

from tqdm import tqdm

from manifoundation.contract import TaskIn
from manifoundation.sdk import Client, delta_pose, force_closure, make_request, object_from_file, wrench

HERE = Path(__file__).resolve().parent
OBJECTS = ["box.npz", "cylinder.npz", "composite.npz", "convex.npz", "blob.ply"]
TASKS: dict[str, TaskIn] = {
    "hold": force_closure(),
    "lift": delta_pose([0.0, 0.0, 0.05]),
    "turn": delta_pose([0.0, 0.0, 0.0], [0.9659, 0.0, 0.0, 0.2588]),  # 30° about z
    "push": wrench(force=[1.0, 0.0, 0.0]),
}
SEEDS = range(5)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--hand", default="leap")
    parser.add_argument("--method", default="auto", help="auto (default): the service's best for the request")
    parser.add_argument("--out", type=Path, default=Path("results.jsonl"))
    parser.add_argument("--url", default=os.environ.get("MANI_URL", "http://127.0.0.1:8000"))
    parser.add_argument("--api-key", default=os.environ.get("MANI_API_KEY"))
    args = parser.parse_args()

    objects = {name: object_from_file(HERE / "data" / name) for name in OBJECTS}
    combos = list(itertools.product(OBJECTS, TASKS, SEEDS))
    requests = [
        make_request(objects[name], TASKS[task], args.hand, method=args.method, seed=seed)
        for name, task, seed in combos
    ]

    with Client(args.url, args.api_key) as client:
        batch = client.submit_batch(requests)
        print(f"batch {batch.id}: {batch.total} requests")
        items = {}
        states: Counter[str] = Counter()
        with tqdm(total=batch.total, unit="req") as bar:
            for item in batch.as_completed(timeout=1800):
                items[item.index] = item
                states[item.state.value] += 1
                bar.update(1)
                bar.set_postfix(states, refresh=False)

    successes: Counter[str] = Counter()
    with args.out.open("w") as out:
        for index in range(len(requests)):  # request order
            item, (name, task, seed) = items[index], combos[index]
            best = item.result.best if item.result is not None else None
            ok = bool(best and best.quality.success)
            successes[task] += ok
            line = {"object": name, "task": task, "seed": seed, "state": item.state.value, "success": ok}
            if item.error is not None:
                line["error"] = item.error.error
            out.write(json.dumps(line) + "\n")
    per_task = len(OBJECTS) * len(SEEDS)
    print("verified successes: " + ", ".join(f"{task} {successes[task]}/{per_task}" for task in TASKS))
    print(f"per-request lines in {args.out}")
    return 0 if states.get("succeeded", 0) == len(requests) else 1


if __name__ == "__main__":
    raise SystemExit(main())
