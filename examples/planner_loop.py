"""A planner-style loop: a sequence of target motions for one object, one synthesis per step.

A task planner (an LLM/VLM, or a motion planner) decides "lift, turn, slide, put down"; for each step the
program asks the service for contacts, forces and a hand pose, checks the quality figures, and moves its model
of the object by the motion it just commanded before planning the next one. Failed or rejected steps are
retried with another seed, the way a planner would re-sample.

    .venv/bin/python examples/planner_loop.py --hand allegro

The default object is the box: with the cylinder, the turn about its own (vertical) axis finds no verified grasp
(every proposal stalls), so that run ends 4/5.
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path

import numpy as np

from manifoundation.contract import DeltaPoseTask, ObjectIn, SynthesisResult
from manifoundation.sdk import Client, JobFailed, RateLimited, TimeoutError, delta_pose, object_from_file

HERE = Path(__file__).resolve().parent

# (what the planner says, translation m, rotation quaternion w x y z)
PLAN = [
    ("lift 5 cm", [0.0, 0.0, 0.05], [1.0, 0.0, 0.0, 0.0]),
    ("turn 45° about z", [0.0, 0.0, 0.0], [0.9239, 0.0, 0.0, 0.3827]),
    ("slide 10 cm along x", [0.10, 0.0, 0.0], [1.0, 0.0, 0.0, 0.0]),
    ("tilt 20° about y", [0.0, 0.0, 0.0], [0.9848, 0.0, 0.1736, 0.0]),
    ("put down", [0.0, 0.0, -0.05], [1.0, 0.0, 0.0, 0.0]),
]


def rotation_matrix(q: np.ndarray) -> np.ndarray:
    w, x, y, z = q / np.linalg.norm(q)
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


def moved(obj: ObjectIn, translation: np.ndarray, quaternion: np.ndarray) -> ObjectIn:
    """The object after the commanded motion (rotation about its centre, then translation)."""
    r = rotation_matrix(np.asarray(quaternion))
    centre = obj.points.mean(axis=0)
    points = (obj.points - centre) @ r.T + centre + translation
    normals = None if obj.normals is None else obj.normals @ r.T
    return obj.model_copy(update={"points": points, "normals": normals, "mesh": None})


def plan_step(client: Client, obj: ObjectIn, task: DeltaPoseTask, hand: str, method: str) -> SynthesisResult | None:
    """One step: up to three seeds until a proposal passes verification; each call asks for up to four proposals
    and stops at the first verified one (``stop_after_verified``), so a good grasp comes back as soon as it exists."""
    for seed in range(3):
        try:
            result = client.synthesize(
                obj, task, hand, method=method, seed=seed, num_proposals=4, stop_after_verified=1, timeout=60
            )
        except (JobFailed, TimeoutError) as exc:
            print(f"    seed {seed}: {exc}")
            continue
        except RateLimited as exc:  # the client already retried with backoff; give the service a moment
            print(f"    busy ({exc}); retrying")
            continue
        best = result.best
        if best is not None and best.quality.success:
            return result
        reason = best.quality.reason if best is not None else "no proposal"
        print(f"    seed {seed}: rejected ({reason})")
    return None


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("object", nargs="?", default=HERE / "data" / "box.npz", type=Path)
    parser.add_argument("--hand", default="leap")
    parser.add_argument("--method", default="auto", help="auto (default): the service's best for the request")
    parser.add_argument("--url", default=os.environ.get("MANI_URL", "http://127.0.0.1:8000"))
    parser.add_argument("--api-key", default=os.environ.get("MANI_API_KEY"))
    args = parser.parse_args()

    obj = object_from_file(args.object, properties={"friction": 0.6, "density": 400})
    done = 0
    with Client(args.url, args.api_key) as client:
        for step, (what, translation, rotation) in enumerate(PLAN, start=1):
            task = delta_pose(translation, rotation)
            print(f"step {step}: {what}")
            result = plan_step(client, obj, task, args.hand, args.method)
            if result is None or result.best is None:
                print("    no verified grasp; the planner would re-plan here")
            else:
                best = result.best
                print(
                    f"    palm {best.palm_position.round(3)} m, residual {best.quality.wrench_residual:.1e}, "
                    f"{sum(result.timings.values()):.2f} s"
                )
                done += 1
            obj = moved(obj, np.asarray(translation), np.asarray(rotation))
    print(f"{done}/{len(PLAN)} steps with a verified grasp")
    return 0 if done == len(PLAN) else 1


if __name__ == "__main__":
    raise SystemExit(main())
