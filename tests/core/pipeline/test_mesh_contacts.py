"""How a refinement attempt ends against verification: its convergence checked on the mesh's contacts, a stalled
or nearly converged pose that verification accepts kept (`manifoundation.core.refine.ending`,
`manifoundation.core.pipeline.run`)."""

import dataclasses
import importlib
from functools import partial

import numpy as np
import pytest

from manifoundation.core.pipeline import SynthesisInput, TaskInput, run_pipeline
from manifoundation.core.robots import get_hand
from research.audit import AuditedGrasp, audit_grasp, third_party_objects

LIFT = np.array([0.0, 0.0, 0.05])


def _allegro_lift(name: str, seed: int) -> tuple[SynthesisInput, object, np.ndarray, np.ndarray]:
    """An Allegro 5 cm lift of a third-party object (2 048 points and its mesh sent), as `mani-lab bench pipeline`
    asks it: (request, mesh, points, normals)."""
    obj = next(o for o in third_party_objects() if o.name == name)
    points, normals = obj.sample(2048, seed)
    inp = SynthesisInput(
        points=points, normals=normals, hand=get_hand("allegro"),
        task=TaskInput("delta_pose", translation=LIFT, rotation=np.array([1.0, 0.0, 0.0, 0.0])),
        method="random_contacts", num_proposals=1, seed=seed, properties={"friction": 0.8},
        mesh_vertices=np.asarray(obj.mesh.vertices), mesh_faces=np.asarray(obj.mesh.faces),
    )  # fmt: skip
    return inp, obj.mesh, points, normals


def _audited(out: object, mesh: object, points: np.ndarray, normals: np.ndarray) -> bool:
    """The outside audit's verdict on a proposal (its own geometry, no code shared with verification)."""
    grasp = AuditedGrasp(out.contact_points, out.forces, out.fingertips, out.palm_position,  # type: ignore[attr-defined]
                         out.palm_quaternion, out.joint_names, out.joint_values)  # type: ignore[attr-defined]  # fmt: skip
    target = np.r_[LIFT / np.linalg.norm(LIFT), np.zeros(3)]
    return bool(audit_grasp("allegro", grasp, mesh, points, normals, mu=0.8, target_wrench=target).passed)


def test_a_convergence_the_mesh_contradicts_goes_on_to_a_verified_grasp(monkeypatch: pytest.MonkeyPatch) -> None:
    """A block whose refinement converged on the points' surface while the mesh's contacts could not produce the
    wrench (verification refused it)."""
    inp, mesh, points, normals = _allegro_lift("block", 2)
    out = run_pipeline(inp).proposals[0]
    assert out.quality.success and out.quality.reason in ("converged", "verified")
    assert _audited(out, mesh, points, normals)

    # trusting the projected contacts (the check skipped) claims convergence that verification refuses
    ending = importlib.import_module("manifoundation.core.refine.ending")
    monkeypatch.setattr(ending, "mesh_agrees", lambda lin, field: True)
    trusted = run_pipeline(inp).proposals[0]
    assert trusted.quality.reason == "converged" and not trusted.quality.success
    assert trusted.quality.failures == ["wrench_residual"]


def test_a_nearly_converged_pose_that_verifies_ends_the_attempt(monkeypatch: pytest.MonkeyPatch) -> None:
    """A cereal box: verification accepts an iterate whose fingertips are within 4 mm before the SCP's own 2 mm
    test holds; the attempt ends there ("verified", fewer iterations) and the outside audit passes the grasp."""
    inp, mesh, points, normals = _allegro_lift("cereal_box", 0)
    inp = dataclasses.replace(inp, close_gaps=False)  # the refinement's own iterations, without the closing stage
    out = run_pipeline(inp).proposals[0]
    assert out.quality.success and out.quality.reason == "verified" and not out.quality.converged
    assert _audited(out, mesh, points, normals)
    run = importlib.import_module("manifoundation.core.pipeline.run")
    monkeypatch.setattr(run, "RefineConfig", partial(run.RefineConfig, verify_within=0.0))  # never asked
    plain = run_pipeline(inp).proposals[0]
    assert plain.quality.reason == "converged" and plain.quality.iterations > out.quality.iterations


def test_a_stalled_attempt_that_verifies_ends_the_search(monkeypatch: pytest.MonkeyPatch) -> None:
    """A Tiago antenna whose first attempt stalls short of the SCP's own tests: verification accepts that pose, so
    no restart runs, and the outside audit passes the grasp."""
    inp, mesh, points, normals = _allegro_lift("tiago_antenna", 0)
    restarts: list[int] = []
    run = importlib.import_module("manifoundation.core.pipeline.run")
    original = run.refine_from_start
    monkeypatch.setattr(run, "refine_from_start", lambda *a, **k: restarts.append(1) or original(*a, **k))
    out = run_pipeline(inp).proposals[0]
    assert out.quality.success and not out.quality.converged and out.quality.reason == "stalled"
    assert not restarts
    assert _audited(out, mesh, points, normals)
