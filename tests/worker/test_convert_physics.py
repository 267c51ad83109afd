"""``options.simulate``: the worker asks the pipeline for the simulated grasp test (by default a check of what it
returns, true a search, false none), and its conversion reports the test in ``quality.physics`` (success requires
that it held). The tests judge grasps with the real test (MuJoCo)."""

from __future__ import annotations

import numpy as np
import trimesh

from manifoundation.contract import SynthesisRequest, SynthesisResult
from manifoundation.core.physics import from_mesh, from_points, simulate_grasp, simulate_motion
from manifoundation.core.pipeline import ProposalOutput, QualityOutput, SynthesisOutput
from manifoundation.core.robots import get_hand
from manifoundation.server.worker.convert import to_input, to_result

PAD_Z, HALF = 0.1, 0.02  # the Panda's pads at joint value q sit at y = ±q, z 0.0585-0.112 in the palm frame


def _request(simulate: bool | None, mesh: bool) -> SynthesisRequest:
    box = trimesh.creation.box(extents=[0.03, 2 * HALF, 0.03])
    box.apply_translation([0.0, 0.0, PAD_Z])
    pts, face = trimesh.sample.sample_surface_even(box, 600, seed=0)
    obj: dict[str, object] = {"points": np.asarray(pts).tolist(), "normals": box.face_normals[face].tolist()}
    if mesh:
        obj["mesh"] = {"vertices": box.vertices.tolist(), "faces": box.faces.tolist()}
    return SynthesisRequest.model_validate({
        "object": obj, "task": {"kind": "force_closure"}, "robot": {"name": "panda_gripper"},
        "options": {"method": "direct_grasp", "simulate": simulate},
    })  # fmt: skip


def _output(q: float, request: SynthesisRequest | None = None) -> SynthesisOutput:
    """A verified Panda proposal with the pads at ±q; judged by the simulated test as the pipeline judges it when
    ``request`` asks for ``simulate``."""
    hand = get_hand("panda_gripper")
    proposal = ProposalOutput(
        contact_points=np.array([[0.0, HALF, PAD_Z], [0.0, -HALF, PAD_Z]]),
        contact_normals=np.array([[0.0, 1.0, 0.0], [0.0, -1.0, 0.0]]), forces=np.zeros((2, 3)),
        fingertips=list(hand.fingertip_links), palm_position=np.zeros(3), palm_quaternion=np.array([1.0, 0, 0, 0]),
        joint_names=list(hand.joint_names), joint_values=np.array([q]),
        quality=QualityOutput(True, True, "converged", 3, 0.0, 0.0, 0.0, 0.0, 0.1),
    )  # fmt: skip
    if request is not None and request.options.simulate is not False:
        _judge(proposal, request)
    return SynthesisOutput(hand="panda_gripper", proposals=[proposal])


def _judge(p: ProposalOutput, request: SynthesisRequest) -> None:
    obj, task = request.object, request.task
    if obj.mesh is not None:
        shape = from_mesh(np.asarray(obj.mesh.vertices, float), np.asarray(obj.mesh.faces, np.int64))
    else:
        assert obj.normals is not None
        shape = from_points(np.asarray(obj.points, float), np.asarray(obj.normals, float))
    assert p.palm_position is not None and p.palm_quaternion is not None and p.joint_values is not None
    grasp = (get_hand("panda_gripper"), p.palm_position, p.palm_quaternion, p.joint_values, p.contact_points,
             p.contact_normals, p.fingertips, shape)  # fmt: skip
    if task.kind == "delta_pose":
        p.physics = simulate_motion(*grasp, np.asarray(task.translation, float), np.asarray(task.rotation, float))
    else:
        p.physics = simulate_grasp(*grasp)


def _physics(result: SynthesisResult) -> tuple[bool, list[str], object]:
    quality = result.proposals[0].quality
    return quality.success, quality.failures, quality.physics


def test_simulate_reports_a_grasp_that_holds() -> None:
    for mesh in (True, False):
        request = _request(True, mesh)
        result = to_result(_output(HALF, request), request, "test", get_hand("panda_gripper"))
        success, failures, physics = _physics(result)
        assert success and failures == [] and physics is not None
        assert result.proposals[0].quality.physics is not None
        p = result.proposals[0].quality.physics
        assert p.held and len(p.trials) == 6 and p.object_pieces == ("hull" if mesh else "point_hull")
        assert np.allclose(p.pregrasp, [HALF + 0.01]) and np.allclose(p.squeeze, [HALF - 0.01])


def test_simulate_turns_a_verified_grasp_that_drops_into_a_failure() -> None:
    request = _request(True, True)
    result = to_result(_output(HALF + 0.02, request), request, "test", get_hand("panda_gripper"))
    success, failures, physics = _physics(result)
    assert not success and failures == ["physics"] and physics is not None


def test_without_simulate_nothing_changes() -> None:
    result = to_result(_output(HALF + 0.02), _request(False, True), "test", get_hand("panda_gripper"))
    assert _physics(result) == (True, [], None)


def test_the_worker_asks_the_pipeline_for_the_test_for_rigid_objects_with_a_robot() -> None:
    hand = get_hand("panda_gripper")
    assert [to_input(_request(v, True), hand).simulate for v in (None, True, False)] == ["check", "search", "off"]
    unset = SynthesisRequest.model_validate({
        "object": {"points": np.random.default_rng(0).normal(size=(64, 3)).tolist()},
        "task": {"kind": "force_closure"}, "robot": {"name": "panda_gripper"},
    })  # fmt: skip
    assert unset.options.simulate is None and to_input(unset, hand).simulate == "check"  # the default tests


def test_a_checked_answer_that_drops_is_no_success() -> None:
    request = _request(None, False)
    result = to_result(_output(HALF + 0.02, request), request, "test", get_hand("panda_gripper"))
    success, failures, physics = _physics(result)
    assert not success and failures == ["physics"] and physics is not None


def test_physics_order_is_held_and_verified_then_held_then_verified() -> None:
    from manifoundation.core.physics import physics_order

    assert physics_order([True, False, True, True], [False, True, True, None]) == [2, 1, 0, 3]
    assert physics_order([], []) == []


def _lift_request(task: dict[str, object]) -> SynthesisRequest:
    box = trimesh.creation.box(extents=[0.03, 2 * HALF, 0.03])
    box.apply_translation([0.0, 0.0, -PAD_Z])  # below the palm turned upside down: the fingers point down
    pts = trimesh.sample.sample_surface_even(box, 200, seed=0)[0]
    return SynthesisRequest.model_validate({
        "object": {"points": np.asarray(pts).tolist(), "mesh": {"vertices": box.vertices.tolist(),
                                                                "faces": box.faces.tolist()}},
        "task": task, "robot": {"name": "panda_gripper"}, "options": {"method": "direct_grasp", "simulate": True},
    })  # fmt: skip


def _down(q: float) -> SynthesisOutput:
    out = _output(q)
    p = out.proposals[0]
    p.palm_quaternion = np.array([0.0, 1.0, 0.0, 0.0])  # 180° about x
    p.contact_points = np.array([[0.0, -HALF, -PAD_Z], [0.0, HALF, -PAD_Z]])
    p.contact_normals = np.array([[0.0, -1.0, 0.0], [0.0, 1.0, 0.0]])
    return out


def test_a_lift_is_reported_as_the_motion_test() -> None:
    lift = {"kind": "delta_pose", "translation": [0.0, 0.0, 0.05]}
    hand, request = get_hand("panda_gripper"), _lift_request(lift)
    out = _down(HALF)
    _judge(out.proposals[0], request)
    held = to_result(out, request, "test", hand).proposals[0].quality
    assert held.success and held.physics is not None and held.physics.test == "motion"
    assert held.physics.trials == [] and held.physics.motion is not None and held.physics.motion.reached
    assert held.physics.motion.translation_error < 0.01 and held.physics.reason == "reached"
    out = _down(HALF + 0.02)
    _judge(out.proposals[0], request)
    dropped = to_result(out, request, "test", hand).proposals[0].quality
    assert not dropped.success and dropped.failures == ["physics"] and dropped.physics is not None
    assert dropped.physics.motion is not None and dropped.physics.motion.dropped
    hold_it = _lift_request({"kind": "force_closure"})
    out = _down(HALF)
    _judge(out.proposals[0], hold_it)
    closure = to_result(out, hold_it, "test", hand).proposals[0].quality
    assert closure.physics is not None and closure.physics.test == "closure" and len(closure.physics.trials) == 6
    assert closure.physics.motion is None
