"""Third-party hands, built as a user's upload is and audited from their packages' original files.

`audit_hand` gives the audit (`research.audit`, which shares no code with `manifoundation.core.robots`) its own model of
a packaged hand: the package's description file read by the audit's kinematics (pytorch-kinematics, MuJoCo), its meshes
found in the package. `grasp_and_audit` asks the pipeline for force-closure grasps of an object and audits every
proposal.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import trimesh

from manifoundation.core.pipeline import SynthesisInput, TaskInput, run_pipeline
from manifoundation.core.robots.hand import Hand
from manifoundation.core.robots.thirdparty import ThirdPartyHand
from research.audit import AuditedGrasp, audit_grasp
from research.audit.hands import AuditHand, HandSpec
from research.audit.objects import sample_surface

SOFT_FINGER = 0.005
"""m: torsional friction radius of a parallel gripper's pads in the closure test (as `research.evaluation.audit`)."""


@dataclass(frozen=True)
class PackageSpec(HandSpec):
    """A packaged hand for the audit: mesh references resolved in the package's own folder."""

    package: ThirdPartyHand | None = None

    def resolve_mesh(self, filename: str) -> Path:
        """The package file a description's mesh reference names."""
        found = self.package.locate(self.path, filename) if self.package is not None else None
        return found if found is not None else Path(filename)


def audit_hand(hand: ThirdPartyHand, fingertips: list[str]) -> AuditHand:
    """The audit's own model of ``hand`` (from the package's files, not from the upload)."""
    return AuditHand(PackageSpec(hand.name, hand.description, hand.palm, tuple(fingertips), package=hand))


@dataclass
class GraspAudit:
    """Force-closure proposals for one object: how many the service called a success and the audit passed.

    Attributes:
        claimed: proposals the service calls a success; audited: of those, the ones the audit passes.
        best_claimed / best_audited: the same for the best (first) proposal.
        failures: the audit's failures of claimed proposals (must stay empty).
    """

    claimed: int
    audited: int
    best_claimed: bool
    best_audited: bool
    failures: list[str]


def grasp_and_audit(
    hand: Hand, checker: AuditHand, mesh: trimesh.Trimesh, *, proposals: int = 4, seed: int = 0, mu: float = 0.8,
    points: int = 2048, method: str = "random_contacts",
) -> GraspAudit:  # fmt: skip
    """Ask for ``proposals`` force-closure grasps of ``mesh`` (points + normals + mesh sent) and audit each."""
    pts, nrm = sample_surface(mesh, points, seed)
    out = run_pipeline(SynthesisInput(
        points=pts, normals=nrm, hand=hand, task=TaskInput("force_closure"), method=method, num_proposals=proposals,
        seed=seed, properties={"friction": mu}, mesh_vertices=np.asarray(mesh.vertices),
        mesh_faces=np.asarray(mesh.faces),
    ))  # fmt: skip
    claimed = audited = 0
    failures: list[str] = []
    best = (False, False)
    for rank, p in enumerate(out.proposals):
        pose = p.pose()
        grasp = AuditedGrasp(p.contact_points, p.forces, p.fingertips, pose.palm_pos, pose.palm_quat,
                             p.joint_names, pose.q)  # fmt: skip
        soft = SOFT_FINGER if len(p.fingertips) == 2 else 0.0
        report = audit_grasp(checker, grasp, mesh, pts, nrm, mu=mu, closure=True, soft_finger=soft)
        ok = bool(p.quality.success)
        claimed += ok
        audited += ok and report.passed
        if ok and not report.passed:
            failures += report.failures
        if rank == 0:
            best = (ok, ok and report.passed)
    return GraspAudit(claimed, audited, best[0], best[1], failures)
