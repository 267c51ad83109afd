"""The two LEAP hands: `leap_hand` is the original LEAP Hand (its joint names, limits and zero pose), `leap_kaizen`
is ghand's "LEAP V1 KAIZEN" redesign, and `leap` still names the latter; the original grasps and passes the audit."""

from __future__ import annotations

import numpy as np
import trimesh

from manifoundation.core.pipeline import SynthesisInput, TaskInput, run_pipeline
from manifoundation.core.robots import get_hand
from research.audit import AuditedGrasp, audit_grasp
from research.audit.objects import sample_surface


def test_which_leap_is_which() -> None:
    assert get_hand("leap") is get_hand("leap_kaizen")
    kaizen, leap = get_hand("leap_kaizen"), get_hand("leap_hand")
    assert kaizen.lower[kaizen.joint_names.index("id9")] < -1.7  # ghand's flexion is negative
    mcp = leap.joint_names.index("if_mcp")
    assert (leap.lower[mcp], leap.upper[mcp]) == (-0.314, 2.23)  # the LEAP Hand's own MCP range
    assert leap.dof == 16 and leap.fingertip_links == ["if_ds", "mf_ds", "rf_ds", "th_ds"]


def test_the_original_leap_hand_holds_a_cylinder_the_audit_agrees() -> None:
    mesh = trimesh.creation.cylinder(radius=0.025, height=0.08, sections=48)
    points, normals = sample_surface(mesh, 1024, 0)
    out = run_pipeline(SynthesisInput(
        points=points, normals=normals, hand=get_hand("leap_hand"), task=TaskInput("force_closure"),
        method="random_contacts", num_proposals=2, seed=0, properties={"friction": 0.8},
        mesh_vertices=np.asarray(mesh.vertices), mesh_faces=np.asarray(mesh.faces),
    ))  # fmt: skip
    claimed = [p for p in out.proposals if p.quality.success]
    assert claimed
    for p in claimed:
        grasp = AuditedGrasp(p.contact_points, p.forces, p.fingertips, p.palm_position, p.palm_quaternion,
                             p.joint_names, p.joint_values)  # fmt: skip
        report = audit_grasp("leap_hand", grasp, mesh, points, normals, mu=0.8, closure=True)
        assert report.passed, report.failures
