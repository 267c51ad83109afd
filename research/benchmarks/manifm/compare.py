"""Side-by-side timing: the ManiFM release's contact-to-pose optimisation vs ours, on the same contacts.

A standalone script (README.md beside it has the recipe for the release's venv and the figures); nothing in the
product or the tests imports it. It starts two long-lived workers, ``manifm_worker.py`` in the release's venv
and ``ours_worker.py`` in ours, sends each the same seeded cases (the box of ``examples/data/box.npz``, Allegro
hand, lift +5 cm in z, four given contacts), alternating which side goes first per case, after one untimed
warm-up case per side, and prints a table per case and a summary.

Usage::

    .venv/bin/python research/benchmarks/manifm/compare.py --manifm-src $MANIFM_SRC \\
        --manifm-python $MANIFM_VENV/bin/python --cases 15
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import subprocess
import sys
import time
from pathlib import Path
from typing import IO, Any

import numpy as np

HERE = Path(__file__).resolve().parent
REPO = HERE.parents[2]


def make_case(points: np.ndarray, normals: np.ndarray, seed: int, translation: list[float]) -> dict[str, Any]:
    """Four contacts on opposing faces of the box: three (fingers) on one face, 15 mm or more apart, and one
    (thumb) on the opposite face within 20 mm of the fingers' mirrored centroid; seeded."""
    rng = np.random.default_rng(seed)
    axis = int(rng.integers(2))  # x or y faces (z is the lift direction)
    sign = 1.0 if rng.random() < 0.5 else -1.0
    face = np.flatnonzero(normals[:, axis] * sign > 0.9)
    back = np.flatnonzero(normals[:, axis] * sign < -0.9)
    for _ in range(1000):
        three = rng.choice(face, 3, replace=False)
        p = points[three]
        if min(np.linalg.norm(p[i] - p[j]) for i, j in ((0, 1), (0, 2), (1, 2))) >= 0.015:
            break
    mirror = p.mean(axis=0)
    mirror[axis] = -mirror[axis]
    near = back[np.linalg.norm(points[back] - mirror, axis=1) <= 0.02]
    thumb = int(rng.choice(near if len(near) else back))
    idx = [int(i) for i in three] + [thumb]
    return {
        "seed": seed, "axis": "xy"[axis], "indices": idx, "contacts": points[idx].tolist(),
        "points": points.tolist(), "normals": normals.tolist(), "translation": translation,
    }  # fmt: skip


class Worker:
    """A worker process: one JSON case per line in, one JSON record per line out."""

    def __init__(self, name: str, argv: list[str], env: dict[str, str], log: IO[str]) -> None:
        self.name = name
        self.proc = subprocess.Popen(argv, stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=log, text=True,
                                     env=env, bufsize=1)  # fmt: skip
        ready = self._read()
        assert ready.get("ready"), f"{name} worker did not start: {ready}"

    def _read(self) -> dict[str, Any]:
        assert self.proc.stdout is not None
        line = self.proc.stdout.readline()
        if not line:
            raise RuntimeError(f"{self.name} worker exited (rc {self.proc.poll()}); see the worker log")
        return dict(json.loads(line))

    def run(self, case: dict[str, Any]) -> dict[str, Any]:
        """Send one case and wait for its record."""
        assert self.proc.stdin is not None
        self.proc.stdin.write(json.dumps(case) + "\n")
        self.proc.stdin.flush()
        return self._read()

    def close(self) -> None:
        """Close stdin and wait for the process."""
        assert self.proc.stdin is not None
        self.proc.stdin.close()
        self.proc.wait(timeout=60)


def drift_mm(given: list[list[float]], final: list[list[float]]) -> float:
    """Mean over the given contacts of the distance to the nearest final contact, mm."""
    g, f = np.asarray(given), np.asarray(final)
    return float(1000 * np.mean(np.min(np.linalg.norm(g[:, None] - f[None], axis=2), axis=1)))


def _stats(xs: list[float]) -> str:
    return f"median {statistics.median(xs):.4f}  mean {statistics.fmean(xs):.4f}"


def _per_solved(seconds: list[float], solved: int) -> str:
    return f"{sum(seconds) / solved:.4f}" if solved else "inf (none solved)"


def report(rows: list[dict[str, Any]], load: list[tuple[float, float, float]]) -> str:
    """The per-case table and the summary, as Markdown."""
    out = [
        "| case | faces | ManiFM init s | ManiFM opt s | ManiFM s/case | it | ManiFM s/it | flag | ours init s "
        "| ours opt s | ours s/case | it | ours s/it | success | ratio case | ratio s/it | drift mm M/o "
        "| M by our verify, penetration mm M/o |",
        "|" + "---|" * 18,
    ]
    for r in rows:
        m, o = r["manifm"], r["ours"]
        out.append(
            f"| {r['seed']} | {r['axis']} | {m['init']:.3f} | {m['opt']:.3f} | {m['case']:.3f} | {m['iterations']} "
            f"| {m['s_it']:.4f} | {m['flag']} | {o['init']:.3f} | {o['opt']:.3f} | {o['case']:.3f} "
            f"| {o['iterations']} | {o['s_it']:.4f} | {o['success']} ({o['flag']}) | {r['ratio_case']:.1f} "
            f"| {r['ratio_it']:.1f} | {m['drift']:.1f} / {o['drift']:.1f} "
            f"| {m['ours_check']['success']} {','.join(m['ours_check']['failures'])} "
            f"{1000 * m['ours_check']['penetration']:.1f} / {1000 * o['penetration']:.1f} |"
        )
    mc, oc = [r["manifm"]["case"] for r in rows], [r["ours"]["case"] for r in rows]
    mo, oo = [r["manifm"]["opt"] for r in rows], [r["ours"]["opt"] for r in rows]
    mi, oi = [r["manifm"]["s_it"] for r in rows], [r["ours"]["s_it"] for r in rows]
    rc, ri = [r["ratio_case"] for r in rows], [r["ratio_it"] for r in rows]
    ms = sum(r["manifm"]["success"] for r in rows)
    os_ = sum(r["ours"]["success"] for r in rows)
    both = sum(r["manifm"]["success"] and r["ours"]["success"] for r in rows)
    checked = sum(r["manifm"]["ours_check"]["success"] for r in rows)
    gap = max(r["manifm"]["ours_check"]["tip_link_gap_max"] for r in rows)
    out += [
        "",
        f"cases: {len(rows)}",
        f"ManiFM s/case: {_stats(mc)}   (opt only: {_stats(mo)})",
        f"ours   s/case: {_stats(oc)}   (refinement only: {_stats(oo)})",
        f"ratio per case (ManiFM/ours): {_stats(rc)}; "
        f"ratio of medians {statistics.median(mc) / statistics.median(oc):.2f}, "
        f"of means {statistics.fmean(mc) / statistics.fmean(oc):.2f}",
        f"ratio opt only: of medians {statistics.median(mo) / statistics.median(oo):.2f}, "
        f"of means {statistics.fmean(mo) / statistics.fmean(oo):.2f}",
        f"ManiFM s/iteration: {_stats(mi)}",
        f"ours   s/iteration: {_stats(oi)}",
        f"ratio per iteration: {_stats(ri)}",
        f"iterations: ManiFM {_stats([r['manifm']['iterations'] for r in rows])}; "
        f"ours {_stats([r['ours']['iterations'] for r in rows])}",
        f"success: ManiFM {ms}/{len(rows)} (its flag 'success'), ours {os_}/{len(rows)} (quality.success), both {both}",
        f"s per solved case (all seconds / cases its own test passes): ManiFM {_per_solved(mc, ms)}, ours "
        f"{_per_solved(oc, os_)}",
        f"ManiFM's final poses by our verification: {checked}/{len(rows)} pass (max tip-link gap between the two "
        f"Allegro models at its poses: {1000 * gap:.2f} mm)",
        f"load average (1, 5, 15 min) at start {load[0]}, at end {load[1]}",
    ]
    return "\n".join(out)


def _row(case: dict[str, Any], m: dict[str, Any], o: dict[str, Any]) -> dict[str, Any]:
    for rec in (m, o):
        rec["s_it"] = rec["opt"] / max(1, rec["iterations"])
        rec["drift"] = drift_mm(case["contacts"], rec["final_contacts"])
    return {
        "seed": case["seed"], "axis": case["axis"], "contacts": case["contacts"], "manifm": m, "ours": o,
        "ratio_case": m["case"] / o["case"], "ratio_it": m["s_it"] / o["s_it"],
    }  # fmt: skip


def main() -> int:
    """Parse the arguments, run the cases, print the table (and write the records with ``--json``)."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--manifm-src", type=Path, required=True, help="work tree of NUS-LinS-Lab/ManiFM")
    ap.add_argument("--manifm-python", type=Path, required=True, help="python of the release's venv")
    ap.add_argument("--ours-python", type=Path, default=REPO / ".venv" / "bin" / "python")
    ap.add_argument("--repo", type=Path, default=REPO, help="our checkout (PYTHONPATH of our worker)")
    ap.add_argument("--box", type=Path, default=REPO / "examples" / "data" / "box.npz")
    ap.add_argument("--cases", type=int, default=15)
    ap.add_argument("--seed", type=int, default=0, help="first case seed (cases use seed, seed+1, ...)")
    ap.add_argument("--steps", type=int, default=100, help="iteration cap, both sides (the release's step_num)")
    ap.add_argument("--mu", type=float, default=1.0, help="friction, both sides (the release's demo uses 1)")
    ap.add_argument("--pool-threads", type=int, default=1, help="threads of the release's ICP pool (0: Pool())")
    ap.add_argument("--log", type=Path, default=Path("manifm_compare_workers.log"), help="workers' stderr")
    ap.add_argument("--json", type=Path, default=None, help="write every record here")
    args = ap.parse_args()

    data = np.load(args.box)
    points, normals = np.asarray(data["points"], dtype=np.float64), np.asarray(data["normals"], dtype=np.float64)
    lift = [0.0, 0.0, 0.05]
    env = dict(os.environ, OMP_NUM_THREADS="1", MKL_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1")
    ours_env = dict(env, PYTHONPATH=str(args.repo.resolve()))
    with args.log.open("w") as log:
        manifm_argv = [str(args.manifm_python), str(HERE / "manifm_worker.py"), "--manifm-src", str(args.manifm_src)]
        manifm = Worker("ManiFM", [*manifm_argv, "--pool-threads", str(args.pool_threads)], env, log)
        ours = Worker("ours", [str(args.ours_python), str(HERE / "ours_worker.py"), "allegro"], ours_env, log)
        common = {"mu": args.mu, "steps": args.steps}
        warm = make_case(points, normals, 10_000 + args.seed, lift) | common
        manifm.run(warm)
        ours.run(warm)
        load = [os.getloadavg()]
        rows = []
        for k in range(args.cases):
            case = make_case(points, normals, args.seed + k, lift) | common
            if k % 2 == 0:
                m, o = manifm.run(case), ours.run(case)
            else:
                o, m = ours.run(case), manifm.run(case)
            m["ours_check"] = ours.run(case | {"joints": m["joints"], "tips": m["tips"]})  # untimed
            rows.append(_row(case, m, o))
            line = f"case {case['seed']}: ManiFM {m['case']:.3f} s ({m['iterations']} it, {m['flag']}), "
            print(line + f"ours {o['case']:.3f} s ({o['iterations']} it, success {o['success']})", file=sys.stderr)
        load.append(os.getloadavg())
        manifm.close()
        ours.close()
    cpu, when = platform.processor() or platform.machine(), time.strftime("%Y-%m-%d %H:%M %Z")
    print(f"# ManiFM release vs ours, {when}, {cpu}, {os.cpu_count()} cores, one thread each\n")
    print(report(rows, load))
    if args.json is not None:
        args.json.write_text(json.dumps({"args": {k: str(v) for k, v in vars(args).items()}, "load": load,
                                         "rows": rows}, indent=1))  # fmt: skip
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
