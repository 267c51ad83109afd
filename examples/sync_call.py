"""One synchronous call: an object file in, a grasp out, printed and saved as JSON and as a 3D view.

    .venv/bin/mani serve &                       # or `make serve` in another terminal
    .venv/bin/python examples/sync_call.py       # then open grasp.html in a browser

``--method direct_grasp`` (the default here) needs no trained network; ``--method network`` uses the CVAE.
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path

from manifoundation.sdk import Client, ManiError, delta_pose, object_from_file, result_figure, result_to_json

HERE = Path(__file__).resolve().parent


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("object", nargs="?", default=HERE / "data" / "box.npz", type=Path)
    parser.add_argument("--hand", default="leap")
    parser.add_argument("--method", default="auto", help="auto (default): the service's best for the request")
    parser.add_argument("--url", default=os.environ.get("MANI_URL", "http://127.0.0.1:8000"))
    parser.add_argument("--api-key", default=os.environ.get("MANI_API_KEY"))
    args = parser.parse_args()

    obj = object_from_file(args.object, properties={"friction": 0.8, "density": 500})
    lift = delta_pose(translation=[0.0, 0.0, 0.05])  # lift the object by 5 cm

    with Client(args.url, args.api_key) as client:
        try:
            result = client.synthesize(obj, lift, args.hand, method=args.method, num_proposals=2, seed=0)
        except ManiError as exc:  # ValidationError, NotFound, RateLimited, TimeoutError, JobFailed, ...
            print(f"synthesis failed: {exc}")
            return 1

    print(f"hand {result.hand}, {len(result.proposals)} proposal(s), model {result.model_version}")
    best = result.best
    if best is None:
        print("the service found no hand pose for this task")
        return 1
    print(f"success {best.quality.success} ({best.quality.reason}, {best.quality.iterations} iterations)")
    print(f"palm position {best.palm_position.round(3)} m, quaternion {best.palm_quaternion.round(3)}")
    for tip, point, force in zip(best.fingertips, best.contact_points, best.forces, strict=True):
        print(f"  {tip:>24}: contact {point.round(3)} m, force {force.round(2)} N")
    print("timings: " + ", ".join(f"{k} {v:.3f} s" for k, v in result.timings.items()))

    result_to_json(result, "grasp.json")
    result_figure(result, obj).write_html("grasp.html", include_plotlyjs=True)
    print("wrote grasp.json and grasp.html")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
