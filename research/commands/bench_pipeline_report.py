"""The tables of `mani-lab bench pipeline`: latency, stages and parts per hand and checkout, ratios, identical answers.

Records are the worker's (`research.commands.bench_pipeline_worker.run_one`), one per spec, in spec order for each
checkout (``records[name][i]`` answers ``specs[i]``).
"""

from __future__ import annotations

from typing import Any

import numpy as np

STAGES = ("prepare", "network", "initialisation", "refinement", "verification", "physics")
IDENTICAL_TOL = 1e-9


def summary(records: list[dict[str, Any]]) -> dict[str, float]:
    """p50/p90/mean latency (s), verified grasps per second (one core, back to back), mean stage seconds, ms per
    linearisation / contact model / guards / SCP solve, best-proposal success and audit figures."""
    wall = np.array([r["wall"] for r in records])
    verified = sum(sum(r["success"]) for r in records)
    out = {"n": float(len(records)), "p50": float(np.median(wall)), "p90": float(np.percentile(wall, 90)),
           "mean": float(wall.mean()), "verified_per_s": verified / max(float(wall.sum()), 1e-12),
           "best_success": float(np.mean([bool(r["success"]) and r["success"][0] for r in records]))}  # fmt: skip
    for s in STAGES:
        out[s] = float(np.mean([r["stages"].get(s, 0.0) for r in records]))
    lin_calls = sum(r["linearise_calls"] for r in records)
    for part in ("linearise", "contacts", "guards"):
        out[f"{part}_ms"] = 1e3 * sum(r[part] for r in records) / max(lin_calls, 1)
    out["solve_ms"] = 1e3 * sum(r["solve"] for r in records) / max(sum(r["solve_calls"] for r in records), 1)
    out["iterations"] = float(np.mean([r["iterations"] for r in records]))
    sources = [src for r in records for src in r.get("sources", [])]
    out["fallback"] = float(np.mean([src == "random_fallback" for src in sources])) if sources else float("nan")
    audited = [r for r in records if r["audit"] is not None]
    out["audited"] = float(len(audited))
    out["audit_best"] = float(np.mean([r["audit"][0] for r in audited])) if audited else float("nan")
    out["false_claims"] = float(sum(c and not a for r in audited for c, a in zip(r["success"], r["audit"],
                                                                               strict=True)))  # fmt: skip
    return out


def identical(a: dict[str, Any], b: dict[str, Any]) -> bool:
    """Same success per proposal and the same pose (palm, joints) within ``IDENTICAL_TOL``."""
    if a["success"] != b["success"] or len(a["answers"]) != len(b["answers"]):
        return False
    return all(np.max(np.abs(np.subtract(x, y))) <= IDENTICAL_TOL for x, y in zip(a["answers"], b["answers"],
                                                                                   strict=True))  # fmt: skip


def largest_difference(a: dict[str, Any], b: dict[str, Any]) -> float:
    """The largest |Δ| between two records' poses (palm position m, quaternion, joints rad); inf if they differ in
    shape."""
    if len(a["answers"]) != len(b["answers"]):
        return float("inf")
    return max((float(np.max(np.abs(np.subtract(x, y)))) for x, y in zip(a["answers"], b["answers"], strict=True)),
               default=0.0)  # fmt: skip


def print_report(specs: list[dict[str, Any]], records: dict[str, list[dict[str, Any]]],
                 load: tuple[float, float, float]) -> None:  # fmt: skip
    """Print one table row per (hand, checkout or method), and with two of them the ratios and the identical
    answers (the second against the first)."""
    from rich.console import Console
    from rich.table import Table

    console = Console(width=200)
    hands = list(dict.fromkeys(s["hand"] for s in specs))
    spec0 = specs[0]
    table = Table(title=f"one request through run_pipeline: set {spec0['set']}, task {spec0['task']}, "
                        f"{spec0['proposals']} proposal(s), method {spec0['method']}, one thread per worker")
    cols = ("hand", "tree", "req", "p50 s", "p90 s", "mean s", "ok/s", "ok %", "prep", "init", "refine",
            "verify", "physics", "iters", "lin ms", "contact", "guards", "solve ms", "audited", "audit %", "false",
            "fallback %")  # fmt: skip
    for c in cols:
        table.add_column(c, justify="left" if c in ("hand", "tree") else "right")
    stats: dict[tuple[str, str], dict[str, float]] = {}
    for hand in hands:
        idx = [i for i, s in enumerate(specs) if s["hand"] == hand]
        for name, recs in records.items():
            s = stats[hand, name] = summary([recs[i] for i in idx])
            table.add_row(hand, name, f"{s['n']:.0f}", f"{s['p50']:.3f}", f"{s['p90']:.3f}", f"{s['mean']:.3f}",
                          f"{s['verified_per_s']:.2f}", f"{100 * s['best_success']:.0f}", f"{s['prepare']:.3f}",
                          f"{s['initialisation']:.3f}", f"{s['refinement']:.3f}", f"{s['verification']:.3f}",
                          f"{s['physics']:.3f}", f"{s['iterations']:.1f}", f"{s['linearise_ms']:.1f}",
                          f"{s['contacts_ms']:.1f}",
                          f"{s['guards_ms']:.1f}", f"{s['solve_ms']:.1f}", f"{s['audited']:.0f}",
                          f"{100 * s['audit_best']:.0f}", f"{s['false_claims']:.0f}",
                          f"{100 * s['fallback']:.0f}")  # fmt: skip
    console.print(table)
    console.print(f"load average during the run (1, 5, 15 min): {load[0]:.2f} {load[1]:.2f} {load[2]:.2f}")
    console.print("ok/s: verified grasps per second (where the simulated test ran, verified = geometric and "
                  "held); ok %: best proposal verified; prep .. physics: mean s per "
                  "request; lin ms: per linearisation, of which contact (real-surface model) and guards (its "
                  "object-point rows); solve ms: per SCP solve; audit %: best proposal passes the outside audit; "
                  "false: claimed successes the audit rejects; fallback %: proposals whose network heatmap was flat "
                  "(random contacts instead)")
    if len(records) == 2:
        current, reference = list(records)
        for hand in hands:
            a, b = stats[hand, current], stats[hand, reference]
            idx = [i for i, s in enumerate(specs) if s["hand"] == hand]
            cur, ref = records[current], records[reference]
            same = sum(identical(cur[i], ref[i]) for i in idx)
            verdicts = sum(cur[i]["success"] == ref[i]["success"] for i in idx)
            gap = max(largest_difference(cur[i], ref[i]) for i in idx)
            console.print(f"{hand}: {reference} / {current}  p50 ×{b['p50'] / a['p50']:.2f}, "
                          f"p90 ×{b['p90'] / a['p90']:.2f}, "
                          f"mean ×{b['mean'] / a['mean']:.2f}; verified/s {a['verified_per_s']:.2f} vs "
                          f"{b['verified_per_s']:.2f}; identical answers {same}/{len(idx)} (same verdicts "
                          f"{verdicts}/{len(idx)}, largest pose difference {gap:.1e}); audit best "
                          f"{100 * a['audit_best']:.0f} % vs {100 * b['audit_best']:.0f} %")  # fmt: skip
