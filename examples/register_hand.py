"""Register a custom hand from a URDF, then use it by name like a built-in one.

    .venv/bin/python examples/register_hand.py

The service validates the URDF with its hardened loader (no external entities, size and link caps, primitive
collision geometry only) in a worker, stores it in the queue backend so every worker can use it, and answers
with the hand's joints and limits. A malformed URDF is a `ValidationError` naming the problem.
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path

from manifoundation.sdk import Client, ValidationError, force_closure, object_from_file

HERE = Path(__file__).resolve().parent


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--urdf", type=Path, default=HERE / "data" / "two_finger.urdf")
    parser.add_argument("--fingertips", default="left_distal,right_distal")
    parser.add_argument("--method", default="auto", help="auto (default): the service's best for the request")
    parser.add_argument("--url", default=os.environ.get("MANI_URL", "http://127.0.0.1:8000"))
    parser.add_argument("--api-key", default=os.environ.get("MANI_API_KEY"))
    args = parser.parse_args()

    fingertips = args.fingertips.split(",")
    with Client(args.url, args.api_key) as client:
        try:
            hand = client.register_robot(
                args.urdf,
                fingertips,
                name="my_two_finger",
                tip_offsets=[[0.0, 0.0, 0.04]] * len(fingertips),  # contact at the end of each distal link
            )
        except ValidationError as exc:
            print(f"the service rejected the URDF: {exc}")
            return 2
        print(f"registered {hand.name}: {hand.dof} joints {hand.joint_names}, fingertips {hand.fingertips}")
        print("hands now available:", ", ".join(r.name for r in client.robots()))

        result = client.synthesize(
            object_from_file(HERE / "data" / "box.npz"), force_closure(), hand.name, method=args.method
        )
        best = result.best
        if best is None:
            print(f"no hand pose found with {hand.name}")
            return 1
        print(f"grasp with {hand.name}: success {best.quality.success}, joints {best.joint_values.round(3)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
