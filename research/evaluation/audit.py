"""The outside check of the service's answers: run the pipeline on third-party objects and audit every proposal.

The audit (`research.audit`) shares no code with refinement or verification: its own kinematics from the hand
packages' description files, the links' meshes, the object's exact mesh, its own friction cones and wrench. A
proposal the service calls a success and the audit rejects is a false claim; the figure that matters is
``false_claims`` (must be 0) and then the share of best proposals that pass.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from manifoundation.core.pipeline import SynthesisInput, TaskInput, run_pipeline
from manifoundation.core.robots import get_hand
from research.audit import AuditedGrasp, ThirdPartyObject, audit_grasp

LIFT = np.array([0.0, 0.0, 0.05])
SOFT_FINGER = 0.005
"""m: a parallel gripper's pads as soft fingers in the closure test (torsional friction radius; the Panda's pads are
17.5 x 18.5 mm); hands with three or more fingertips are judged with point contacts."""


@dataclass
class AuditRow:
    """One proposal: what the service said and what the audit found."""

    hand: str
    object: str
    task: str
    rank: int
    claimed: bool
    audited: bool
    failures: list[str]


def audit_service(
    hand_name: str, obj: ThirdPartyObject, task: str, *, num_points: int = 2048, proposals: int = 2,
    method: str = "random_contacts", seed: int = 0, mu: float = 0.8, send_mesh: bool = True,
) -> list[AuditRow]:  # fmt: skip
    """Ask the pipeline for ``proposals`` grasps of ``obj`` (task "lift": 5 cm up, or "closure") and audit each.

    Args:
        hand_name: a built-in hand.
        obj: a third-party object (its exact mesh is the audit's truth).
        task: "lift" or "closure".
        num_points: surface samples sent (with the mesh's face normals, as a caller would).
        proposals, method, seed: the request's options.
        mu: friction sent and audited.
        send_mesh: also send the mesh (else the service knows only the points).
    """
    points, normals = obj.sample(num_points, seed)
    kind = TaskInput("force_closure") if task == "closure" else TaskInput(
        "delta_pose", translation=LIFT, rotation=np.array([1.0, 0.0, 0.0, 0.0]))  # fmt: skip
    inp = SynthesisInput(
        points=points, normals=normals, hand=get_hand(hand_name), task=kind, method=method,
        num_proposals=proposals, seed=seed, properties={"friction": mu},
        mesh_vertices=np.asarray(obj.mesh.vertices) if send_mesh else None,
        mesh_faces=np.asarray(obj.mesh.faces) if send_mesh else None,
    )  # fmt: skip
    out = run_pipeline(inp)
    target = None if task == "closure" else np.r_[LIFT / np.linalg.norm(LIFT), np.zeros(3)]
    rows = []
    for rank, p in enumerate(out.proposals):
        pose = p.pose()
        grasp = AuditedGrasp(p.contact_points, p.forces, p.fingertips, pose.palm_pos, pose.palm_quat,
                             p.joint_names, pose.q)  # fmt: skip
        soft = SOFT_FINGER if len(grasp.fingertips) == 2 else 0.0
        report = audit_grasp(hand_name, grasp, obj.mesh, points, normals, mu=mu, target_wrench=target,
                             closure=task == "closure", soft_finger=soft)  # fmt: skip
        rows.append(AuditRow(hand_name, obj.name, task, rank, p.quality.success, report.passed,
                             list(report.failures)))  # fmt: skip
    return rows
