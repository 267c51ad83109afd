"""`mani-lab bench deformable`: MuJoCo flex simulation speed and stability per material and shape.

For every shape kind of each material and ``--bodies`` seeds, with the properties at both ends of their ranges
(soft: every stiffness at its low end; stiff: at its high end), it runs one rollout of the data generator's
kind (cloth and rope: one point dragged by 0.4 s; plasticine: the top point pressed by 0.2 s) and reports
steps/s, seconds per rollout, the share of rollouts that stayed stable (no NaN, no MuJoCo reset) and the
grasp tracking error (largest distance between a grasped vertex and its path's end at release).

With ``--registration N`` it also measures the unordered-target registration
(`manifoundation.core.deformable.registration`) on N simulated pairs per material: the start cloud, the rollout
shuffled, the optimal-transport motion against the simulated one. With ``--rebuilt N`` it measures the bodies the
service rebuilds from clouds for ``options.simulate_rollout`` (`manifoundation.core.deformable.reconstruct`): N
generated bodies per material, the ground-truth manipulation simulated on the generator's mesh and on the body rebuilt
from its cloud, the second rollout scored against the first by the shape metric.

Example:
    mani-lab bench deformable --materials cloth,rope,plasticine --bodies 2 --registration 10 --rebuilt 10
"""

from __future__ import annotations

import argparse
from typing import Any

EXIT_OK = 0


def register(subparsers: Any) -> None:
    """Add ``deformable`` to the ``mani-lab bench`` sub-commands."""
    p = subparsers.add_parser("deformable", help="flex simulation steps/s and stability per material",
                              description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--materials", default="cloth,rope,plasticine", help="comma-separated materials")
    p.add_argument("--bodies", type=int, default=2, help="seeds per shape kind (default 2)")
    p.add_argument("--registration", type=int, default=0,
                   help="also measure optimal-transport registration on this many simulated pairs per material")
    p.add_argument("--rebuilt", type=int, default=0,
                   help="also compare rollouts on bodies rebuilt from clouds with the generator's, N per material")
    p.add_argument("--seed", type=int, default=0)
    p.set_defaults(func=run)


def _extreme(material: str, stiff: bool) -> dict[str, float]:
    from manifoundation.core.deformable.materials import RANGES

    out = {}
    for name, (lo, hi, _) in RANGES[material].items():
        out[name] = hi if stiff == (name != "poisson_ratio") else lo
        if name in ("friction", "density", "poisson_ratio"):
            out[name] = (lo + hi) / 2
    return out


def run(args: argparse.Namespace) -> int:
    import numpy as np
    from rich.console import Console
    from rich.table import Table

    from manifoundation.core.deformable.shapes import KINDS, make_body
    from manifoundation.core.deformable.simulate import simulate

    table = Table(title="MuJoCo 4.0 flex rollouts (discrete integrator, one thread)")
    for col in ("material", "kind", "properties", "vertices", "rollouts", "stable %", "steps/s", "s/rollout",
                "track err mm"):
        table.add_column(col, justify="right" if col not in ("material", "kind", "properties") else "left")
    for material in args.materials.split(",") if args.bodies else []:
        for kind in KINDS[material]:
            for stiff in (False, True):
                rows = []
                for b in range(args.bodies):
                    body = make_body(material, kind, args.seed + b, _extreme(material, stiff))
                    pts = body.points
                    if material == "plasticine":
                        i, motion = int(np.argmax(pts[:, 2])), np.array([[0.0, 0.0, -0.2 * body.size]])
                    else:
                        i, motion = int(np.argmin(pts[:, 0])), np.array([[0.4 * body.size, 0.0, 0.0]])
                    r = simulate(body, np.array([i]), motion)
                    rows.append((len(body.vertices), r.stable, r.steps / r.seconds, r.seconds, r.tracking_error))
                a = np.array(rows, dtype=np.float64)
                table.add_row(material, kind, "stiff" if stiff else "soft", f"{a[:, 0].mean():.0f}", str(len(a)),
                              f"{100 * a[:, 1].mean():.0f}", f"{np.median(a[:, 2]):.0f}",
                              f"{np.median(a[:, 3]):.2f}", f"{1000 * np.max(a[:, 4]):.2f}")
    console = Console(width=140)
    console.print(table)
    if args.registration:
        console.print(registration_table(args.materials.split(","), args.registration, args.seed))
    if args.rebuilt:
        console.print(rebuilt_table(args.materials.split(","), args.rebuilt, args.seed))
    return EXIT_OK


def registration_table(materials: list[str], pairs: int, seed: int) -> Any:
    """Registered motion (CPD + OT, and OT alone) vs the simulated one on shuffled target clouds, per material."""
    import time

    import numpy as np
    from rich.table import Table

    from manifoundation.core.deformable.metrics import NORMALISED_SIDE
    from manifoundation.core.deformable.procedures import random_manipulation
    from manifoundation.core.deformable.registration import transport_motion
    from manifoundation.core.deformable.shapes import KINDS, make_body
    from manifoundation.core.deformable.simulate import simulate

    table = Table(title="unordered targets: per-point motion by registration vs the simulated one "
                        "(errors in the 2 m normalised cube)")
    for col in ("material", "method", "pairs", "median |motion|", "median error", "mean error", "p90 error",
                "exact matches %", "ms a pair"):
        table.add_column(col, justify="left" if col in ("material", "method") else "right")
    for material in materials:
        rows: dict[str, list[Any]] = {"cpd": [], "ot": []}
        sizes = []
        rng = np.random.default_rng(seed)
        for k in range(pairs):
            body = make_body(material, KINDS[material][k % len(KINDS[material])], seed + k)
            m = random_manipulation(body, rng)
            out = simulate(body, m.contacts, m.motions)
            shuffled = out.cloud[rng.permutation(len(out.cloud))]
            truth = out.cloud - body.points
            scale = NORMALISED_SIDE / body.size
            sizes.append(np.linalg.norm(truth, axis=1) * scale)
            for method in rows:
                t0 = time.perf_counter()
                est = transport_motion(body.points, shuffled, method=method)
                rows[method].append((np.linalg.norm(est - truth, axis=1), scale, time.perf_counter() - t0))
        for method, got in rows.items():
            e = np.concatenate([d * s for d, s, _ in got])
            exact = np.concatenate([d < 1e-9 for d, _, _ in got])
            table.add_row(material, "CPD + OT" if method == "cpd" else "OT", str(pairs),
                          f"{np.median(np.concatenate(sizes)):.3f}", f"{np.median(e):.3f}", f"{e.mean():.3f}",
                          f"{np.percentile(e, 90):.3f}", f"{100 * exact.mean():.1f}",
                          f"{1000 * np.median([t for _, _, t in got]):.0f}")
    return table


def rebuilt_table(materials: list[str], bodies: int, seed: int) -> Any:
    """Rollouts on bodies rebuilt from their clouds vs on the generators' meshes, same manipulation."""
    import time

    import numpy as np
    from rich.table import Table

    from manifoundation.core.deformable.metrics import shape_score
    from manifoundation.core.deformable.procedures import random_manipulation
    from manifoundation.core.deformable.reconstruct import body_from_cloud
    from manifoundation.core.deformable.shapes import KINDS, make_body
    from manifoundation.core.deformable.simulate import simulate

    table = Table(title="bodies rebuilt from clouds (simulate_rollout) vs the generator's meshes: the rebuilt "
                        "rollout scored against the native one (2 m normalised cube)")
    for col in ("material", "bodies", "agree by the metric %", "median top-mean error", "median |motion|",
                "error / motion", "ms to rebuild"):
        table.add_column(col, justify="left" if col == "material" else "right")
    for material in materials:
        agree, errors, motions, builds = [], [], [], []
        rng = np.random.default_rng(seed)
        for k in range(bodies):
            body = make_body(material, KINDS[material][k % len(KINDS[material])], seed + k)
            m = random_manipulation(body, rng)
            native = simulate(body, m.contacts, m.motions).cloud
            t0 = time.perf_counter()
            rebuilt = body_from_cloud(material, body.points, body.normals, body.properties)
            builds.append(time.perf_counter() - t0)
            run = simulate(rebuilt.body, rebuilt.to_simulator(body.points[m.contacts]), m.motions)
            score = shape_score(material, body.points, native, rebuilt.cloud(run.vertices))
            still = shape_score(material, body.points, native, body.points)
            agree.append(score.success)
            errors.append(score.top_mean_error)
            motions.append(still.top_mean_error)
        e, d = np.array(errors), np.array(motions)
        table.add_row(material, str(bodies), f"{100 * np.mean(agree):.0f}", f"{np.median(e):.3f}",
                      f"{np.median(d):.3f}", f"{np.median(e / np.maximum(d, 1e-12)):.2f}",
                      f"{1000 * np.median(builds):.0f}")
    return table
