"""Table I protocol: for each test case and method, run the pipeline and count docs/evaluation.md successes.


Methods (all through `manifoundation.core.pipeline.run_pipeline`, same hand, same case, same seed):

- ``network``: network (K proposals) → NMS selection → initialisation → SOCP refinement ("Ours").
- ``network_no_refine``: the same initial poses without refinement ("Ours w/o refinement": the initial pose is
  the rigid fit of the resting fingertips to the predicted contacts).
- ``random_contacts``: random spread contacts → initialisation → refinement (baseline).
- ``direct_grasp``: open hand moved to the object centre, fingers closed on contact, forces by Eq. (6).

For the network methods the table also counts ``fallback`` cases, where no proposal came from the network's
own contacts (every heatmap was flat, so the pipeline refined random contacts instead, `contact_source =
"random_fallback"`): a network success is only a network result when that count is low.

A case succeeds when its best proposal passes verification (wrench residual, tips within 5 mm, penetration and
self-collision ≤ 1 mm). Articulated cases use the joint task (joint_motion with the case's joint). With
``audit``, a rigid case's claimed success is re-checked by the outside audit (`research.audit`: its own kinematics,
the links' meshes, the exact object mesh, its own cones and wrench; the target wrench [m Δx; I Δθ] from the case's
stored motion and the mesh's mass properties); ``audited`` counts the claims it confirms. ``iterations`` holds
the refinement iterations of every proposal.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from research.evaluation.testset import TestCase

if TYPE_CHECKING:
    from manifoundation.core.pipeline import SynthesisInput
    from manifoundation.core.robots.hand import Hand

METHODS = ("network", "network_no_refine", "random_contacts", "direct_grasp")


@dataclass
class MethodResult:
    method: str
    hand: str
    split: str
    successes: int = 0
    cases: int = 0
    seconds: float = 0.0
    failures: dict[str, int] = field(default_factory=dict)
    fallbacks: int = 0  # network methods: cases where no proposal used the network's contacts
    audited: int = 0  # claimed successes the outside audit confirms (when asked)
    iterations: list[int] = field(default_factory=list)  # per proposal

    @property
    def rate(self) -> float:
        return self.successes / self.cases if self.cases else 0.0


def synthesis_input(
    case: TestCase, hand: Hand, method: str, num_proposals: int, seed: int, max_iterations: int
) -> SynthesisInput:
    """The `SynthesisInput` of one case for one method."""
    from manifoundation.core.pipeline import JointInput, SynthesisInput, TaskInput

    joint = None
    if case.articulated:
        joint = JointInput(case.joint_type, case.joint_axis, case.joint_origin, np.ones(len(case.points), bool))
        task = TaskInput(kind="joint_motion", delta=case.joint_amount)
    else:
        task = TaskInput(kind="point_motion", motion=case.motion)
    pipeline_method = {"network_no_refine": "network"}.get(method, method)
    return SynthesisInput(
        points=case.points,
        normals=case.normals,
        hand=hand,
        task=task,
        material="articulated" if case.articulated else "rigid",
        properties={"friction": case.friction},
        mask=None if case.mask.all() else case.mask,
        joint=joint,
        mesh_vertices=case.mesh_vertices,
        mesh_faces=case.mesh_faces,
        method=pipeline_method,
        num_proposals=num_proposals,
        refine=method != "network_no_refine",
        max_iterations=max_iterations,
        seed=seed,
        hand_key=hand.name,
    )


def evaluate(
    cases: list[TestCase],
    hand: Hand,
    methods: tuple[str, ...],
    predictor: Any | None,
    num_proposals: int = 4,
    seed: int = 0,
    max_iterations: int = 100,
    progress: bool = True,
    audit: bool = False,
) -> list[MethodResult]:
    """Run every method on every case; one `MethodResult` per method (``audit``: see the module docstring)."""
    from tqdm import tqdm

    from manifoundation.core.pipeline import run_pipeline

    split = cases[0].split if cases else ""
    results = {m: MethodResult(m, hand.name, split) for m in methods}
    bar = tqdm(total=len(cases) * len(methods), disable=not progress, desc=f"{hand.name} {split}")
    for i, case in enumerate(cases):
        for m in methods:
            t0 = time.perf_counter()
            inp = synthesis_input(case, hand, m, 1 if m == "direct_grasp" else num_proposals, seed + i, max_iterations)
            out = run_pipeline(inp, predictor if m.startswith("network") else None)
            r = results[m]
            r.cases += 1
            r.seconds += time.perf_counter() - t0
            if m.startswith("network") and all(p.contact_source == "random_fallback" for p in out.proposals):
                r.fallbacks += 1
            best = out.best
            r.iterations += [p.quality.iterations for p in out.proposals]
            if best is not None and best.quality.success:
                r.successes += 1
                if audit and not case.articulated:
                    r.audited += int(audit_case(case, hand.name, best))
            elif best is not None:
                for f in best.quality.failures or [best.quality.reason]:
                    key = f.split(":")[0]
                    r.failures[key] = r.failures.get(key, 0) + 1
            bar.update(1)
            bar.set_postfix({k: f"{v.rate:.0%}" for k, v in results.items()})
    bar.close()
    return list(results.values())


def table(rows: list[MethodResult]) -> str:
    """Markdown table: one row per method, one column per (hand, split)."""
    cols = sorted({(r.hand, r.split) for r in rows})
    methods = list(dict.fromkeys(r.method for r in rows))
    head = "| method | " + " | ".join(f"{h} {s}" for h, s in cols) + " |"
    lines = [head, "|" + "---|" * (len(cols) + 1)]
    for m in methods:
        cells = []
        for c in cols:
            r = next((x for x in rows if x.method == m and (x.hand, x.split) == c), None)
            fallback = f", {r.fallbacks} fallback" if r and r.fallbacks else ""
            cells.append(f"{r.rate:.1%} ({r.successes}/{r.cases}{fallback})" if r else "")
        lines.append(f"| {m} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def audit_case(case: TestCase, hand_name: str, proposal: Any) -> bool:
    """Whether the outside audit confirms ``proposal`` for a rigid ``case`` (see the module docstring)."""
    import trimesh

    from research.audit import AuditedGrasp, audit_grasp

    mesh = trimesh.Trimesh(case.mesh_vertices, case.mesh_faces, process=False)
    assert case.delta_x is not None and case.delta_theta is not None
    target = np.r_[mesh.mass * case.delta_x, np.asarray(mesh.moment_inertia) @ case.delta_theta]
    p = proposal
    grasp = AuditedGrasp(p.contact_points, p.forces, p.fingertips, p.palm_position, p.palm_quaternion,
                         p.joint_names, p.joint_values)  # fmt: skip
    soft = 0.005 if len(grasp.fingertips) == 2 else 0.0  # a parallel gripper's pads (research.evaluation.audit)
    report = audit_grasp(hand_name, grasp, mesh, case.points, case.normals, mu=case.friction, target_wrench=target,
                         soft_finger=soft, centre=np.asarray(mesh.center_mass))  # fmt: skip
    return bool(report.passed)
