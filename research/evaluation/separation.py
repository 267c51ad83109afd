"""Does a deformable metric separate? Issue 59's acceptance test of the 3D rule (`metrics.solid_success`).

A metric is accepted only if it tells a reached target from a missed one on the evaluation's own cases
(`research.evaluation.deformable`): the target's own press replayed (``ground_truth``) succeeds in ≥ 95 % of the
cases, random points with random motions (``random_motion``, the paper's baseline) in ≤ 5 %, random points with the
target's motion at them (``random_target_motion``) in ≤ 20 %. `separation` reads those rates from a report, under
the metric's rule and, beside it, under the paper's own 3D rule (all points < 0.5 cm and the 100 most-moving
< 5 cm in the 2 m cube, `metrics.paper_solid_success`); every other method in the run (the service's answers) is
listed with its rates, judged by nothing.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from manifoundation.core.deformable.metrics import paper_solid_success

if TYPE_CHECKING:
    from rich.console import Console

    from research.evaluation.deformable import DeformableReport

# method → (bound, ≥ or ≤): the decision's criteria, in %
CRITERIA = {"ground_truth": (95.0, ">="), "random_motion": (5.0, "<="), "random_target_motion": (20.0, "<=")}


@dataclass(frozen=True)
class SeparationRow:
    """One method over every case of a material: success % by the rule and by the paper's rule, median closure
    and median most-moving error; its criterion (None: none) and whether the rule's rate meets it."""

    method: str
    cases: int
    success: float
    paper_success: float
    closure: float
    top_mean_error: float
    criterion: str | None
    met: bool | None


def separation(report: DeformableReport, material: str, methods: tuple[str, ...]) -> list[SeparationRow]:
    """The rows of ``methods`` (in that order) over all of the report's ``material`` cases, every split together."""
    idx = [i for i, c in enumerate(report.cases) if c.material == material]
    rows = []
    for method in methods:
        rs = [r for i in idx for r in report.results[i] if r.method == method]
        if not rs:
            continue
        rate = 100.0 * float(np.mean([r.success for r in rs]))
        bound = CRITERIA.get(method)
        met = None if bound is None else (rate >= bound[0] if bound[1] == ">=" else rate <= bound[0])
        rows.append(SeparationRow(method, len(rs), rate, 100.0 * float(np.mean([paper_solid_success(r.score)
                                                                                 for r in rs])),
                                  float(np.median([r.score.closure for r in rs])),
                                  float(np.median([r.score.top_mean_error for r in rs])),
                                  None if bound is None else f"{bound[1]} {bound[0]:.0f} %", met))  # fmt: skip
    return rows


def accepted(rows: list[SeparationRow]) -> bool | None:
    """Whether every criterion holds (None: a criterion's method is missing from the run)."""
    judged = {r.method: r.met for r in rows if r.met is not None}
    if set(judged) != set(CRITERIA):
        return None
    return all(judged.values())


def print_separation(console: Console, report: DeformableReport, materials: list[str],
                     methods: tuple[str, ...]) -> list[dict[str, object]]:  # fmt: skip
    """Print each material's separation table and verdict; return the rows (JSON-ready)."""
    from rich.table import Table

    out: list[dict[str, object]] = []
    for material in materials:
        rows = separation(report, material, methods)
        if not rows:
            continue
        bodies = {c.body.id: c.body.kind for c in report.cases if c.material == material}
        table = Table(title=f"{material}: does the metric separate? {rows[0].cases} cases on {len(bodies)} bodies "
                            f"of {len(set(bodies.values()))} kinds (issue 59's criteria)")  # fmt: skip
        for col in ("method", "cases", "success % (rule)", "paper's all-points rule %", "median closure",
                    "median top err", "criterion", "met"):
            table.add_column(col, justify="left" if col in ("method", "criterion") else "right")
        for r in rows:
            table.add_row(r.method, str(r.cases), f"{r.success:.1f}", f"{r.paper_success:.1f}", f"{r.closure:.2f}",
                          f"{r.top_mean_error:.3f}", r.criterion or "-", "-" if r.met is None else
                          ("yes" if r.met else "no"))  # fmt: skip
            out.append({"material": material, **vars(r)})
        console.print(table)
        verdict = accepted(rows)
        console.print(f"{material}: metric " + ("accepted" if verdict else "not accepted" if verdict is False
                                                else "not judged (run ground_truth, random_motion and "
                                                "random_target_motion)"))  # fmt: skip
    return out
