"""The proto mirrors the contract field for field, and the one conversion keeps validation in pydantic."""

from __future__ import annotations

import typing

import numpy as np
import pytest
from pydantic import BaseModel, ValidationError

from manifoundation import contract as schemas
from manifoundation.contract import BatchPublic, JobPublic, RobotRegister, SynthesisRequest, SynthesisResult
from manifoundation.contract.protos.convert import from_proto, to_data, to_proto
from manifoundation.contract.protos.v1 import manifoundation_pb2 as pb

from ..helpers import request_body

TASKS = {"DeltaPoseTask", "PointMotionTask", "TargetPointsTask", "WrenchTask", "ForceClosureTask", "JointMotionTask"}
OBSTACLES = {"BoxObstacleIn", "MeshObstacleIn", "PointCloudObstacleIn"}
UNIONS = TASKS | OBSTACLES  # members of a discriminated union: their `kind` is the proto's oneof


def _models(root: type[BaseModel], seen: dict[str, type[BaseModel]]) -> dict[str, type[BaseModel]]:
    """Every contract model reachable from ``root`` by its fields, by name."""
    if root.__name__ in seen:
        return seen
    seen[root.__name__] = root
    for field in root.model_fields.values():
        stack = [field.annotation]
        while stack:
            kind = stack.pop()
            if isinstance(kind, type) and issubclass(kind, BaseModel):
                _models(kind, seen)
            stack.extend(typing.get_args(kind))
    return seen


ROOTS = (SynthesisRequest, SynthesisResult, JobPublic, BatchPublic, RobotRegister, schemas.RobotPublic,
         schemas.PlanRequest, schemas.PlanResult)  # fmt: skip
MODELS = {name: m for root in ROOTS for name, m in _models(root, {}).items()}


@pytest.mark.parametrize("name", sorted(MODELS))
def test_every_contract_field_has_a_proto_field(name: str) -> None:
    message = getattr(pb, name).DESCRIPTOR
    wanted = set(MODELS[name].model_fields) - ({"kind"} if name in UNIONS else set())
    assert wanted <= set(message.fields_by_name), f"{name}: the proto lacks {wanted - set(message.fields_by_name)}"
    assert set(message.fields_by_name) <= set(MODELS[name].model_fields), f"{name}: the proto has extra fields"


def test_task_union_has_every_kind() -> None:
    kinds = {m.model_fields["kind"].default for m in MODELS.values() if m.__name__ in TASKS}
    assert set(pb.TaskIn.DESCRIPTOR.fields_by_name) == kinds


def test_obstacle_union_has_every_kind() -> None:
    kinds = {m.model_fields["kind"].default for m in MODELS.values() if m.__name__ in OBSTACLES}
    assert set(pb.ObstacleIn.DESCRIPTOR.fields_by_name) == kinds


def test_plan_request_round_trip_keeps_every_value() -> None:
    points = np.random.default_rng(0).normal(size=(64, 3)) * 0.03
    plan = schemas.PlanRequest.model_validate({
        "object": {"points": points, "properties": {"friction": 0.7}},
        "start": {"position": [0, 0, 0.1]},
        "waypoints": [{"position": [0.1, 0, 0.2], "quaternion": [0, 0, 0, 2]}, {"position": [0.2, 0, 0.1]}],
        "scene": {"support_plane": {"height": 0.0}, "obstacles": [
            {"kind": "box", "name": "wall", "size": [0.02, 0.4, 0.3], "pose": {"position": [0.05, 0, 0.15]}},
            {"kind": "points", "points": points[:5], "resolution": 0.02},
            {"kind": "mesh", "vertices": points[:4], "faces": [[0, 1, 2], [0, 2, 3]]},
        ]},
        "robot": {"name": "test_gripper"},
        "options": {"seed": 3, "repair": "report", "contacts": False, "time_limit": 2.5},
    })  # fmt: skip
    message = to_proto(plan, pb.PlanRequest)
    assert [o.WhichOneof("kind") for o in message.scene.obstacles] == ["box", "points", "mesh"]
    back = from_proto(pb.PlanRequest.FromString(message.SerializeToString()), schemas.PlanRequest)
    assert back.model_dump_json() == plan.model_dump_json()  # (0, 0, 0, 2) was normalised once, on input
    np.testing.assert_array_equal(back.waypoints[0].quaternion, [0, 0, 0, 1])


def test_request_round_trip_keeps_every_value() -> None:
    request = SynthesisRequest.model_validate(request_body("test_gripper", seed=7, num_proposals=2))
    message = to_proto(request, pb.SynthesisRequest)
    assert message.object.points.dtype == "float64" and list(message.object.points.shape) == [128, 3]
    assert message.task.WhichOneof("kind") == "force_closure"
    back = from_proto(pb.SynthesisRequest.FromString(message.SerializeToString()), SynthesisRequest)
    assert np.array_equal(back.object.points, request.object.points)
    assert back.options == request.options and back.robot == request.robot
    assert back.object.properties.friction == 0.8 and back.task.kind == "force_closure"


def test_unset_fields_take_the_contract_defaults() -> None:
    request = SynthesisRequest.model_validate(request_body("test_gripper"))
    message = to_proto(request, pb.SynthesisRequest)
    message.ClearField("options")
    back = from_proto(message, SynthesisRequest)
    assert back.options == schemas.SynthesisOptions()


def _message() -> pb.SynthesisRequest:
    return to_proto(SynthesisRequest.model_validate(request_body("test_gripper")), pb.SynthesisRequest)


@pytest.mark.parametrize(
    ("spoil", "field", "problem"),
    [
        (lambda m: setattr(m.object.points, "dtype", "object"), "object.points", "not allowed"),
        (lambda m: setattr(m.object.points, "data", m.object.points.data[:-8]), "object.points", "bytes"),
        (lambda m: m.object.points.shape.__setitem__(0, 127), "object.points", "bytes"),
        (lambda m: setattr(m.options, "method", "telepathy"), "options.method", ""),
        (lambda m: m.ClearField("task"), "task", ""),
        (lambda m: setattr(m.task.joint_motion, "delta", 0.0), "task.joint_motion", "delta"),
    ],
)
def test_bad_input_names_the_field(spoil: typing.Any, field: str, problem: str) -> None:
    message = _message()
    spoil(message)
    with pytest.raises(ValidationError) as caught:
        from_proto(message, SynthesisRequest)
    paths = [".".join(str(p) for p in e["loc"]) for e in caught.value.errors()]
    assert any(p.startswith(field) for p in paths), paths
    assert problem in str(caught.value)


def test_result_and_job_to_proto() -> None:
    rows = np.arange(9.0).reshape(3, 3)
    quality = schemas.Quality(success=True, converged=True, reason="converged", iterations=0, wrench_residual=0,
                              max_tip_distance=0, penetration_depth=0, self_collision_depth=0)  # fmt: skip
    proposal = schemas.Proposal(contact_points=rows, contact_normals=rows, forces=rows, fingertips=["a", "b", "c"],
                                palm_position=np.zeros(3), palm_quaternion=np.array([1.0, 0, 0, 0]),
                                joint_names=["j"], joint_values=np.array([0.5]), quality=quality,
                                contact_source="given_moved",
                                contact_shift=np.array([0.001, 0.002, 0.007]))  # fmt: skip
    result = SynthesisResult(hand="h", model_version="m", proposals=[proposal], timings={"network": 0.25})
    job = JobPublic(id="j1", state=schemas.JobState.SUCCEEDED, created_at=1.0, result=result)
    message = to_proto(job, pb.JobPublic)
    assert message.state == "succeeded" and message.result.timings["network"] == 0.25
    assert message.result.proposals[0].quality.iterations == 0 and not message.HasField("error")
    back = from_proto(message, JobPublic, answer=True)
    assert back.result is not None and np.array_equal(back.result.proposals[0].forces, rows)
    assert back.result.proposals[0].quality == quality
    shift = back.result.proposals[0].contact_shift  # issue 62: per-contact shift of given contacts, over gRPC too
    assert shift is not None and np.array_equal(shift, [0.001, 0.002, 0.007])
    assert to_data(pb.BatchPublic(counts={"queued": 2}))["counts"] == {"queued": 2}


def test_contacts_without_a_robot_come_back_without_a_hand() -> None:
    rows = np.arange(6.0).reshape(2, 3)
    quality = schemas.Quality(success=False, converged=False, reason="deformable_open_loop", iterations=0,
                              wrench_residual=0, max_tip_distance=0, penetration_depth=0,
                              self_collision_depth=0)  # fmt: skip
    proposal = schemas.Proposal(contact_points=rows, contact_normals=rows, forces=rows, quality=quality,
                                contact_motions=rows, rollout_points=rows, shape_error=0.1)  # fmt: skip
    message = to_proto(SynthesisResult(model_version="m", proposals=[proposal]), pb.SynthesisResult)
    back = from_proto(pb.SynthesisResult.FromString(message.SerializeToString()), SynthesisResult, answer=True)
    [got] = back.proposals
    assert back.hand is None and got.palm_position is None and got.palm_quaternion is None
    assert got.fingertips == [] and len(got.joint_values) == 0 and got.shape_error == 0.1
    assert got.contact_shift is None  # optional: unset for methods other than "contacts"
    assert got.rollout_points is not None and np.array_equal(got.rollout_points, rows)
