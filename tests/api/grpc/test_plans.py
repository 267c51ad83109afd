"""SubmitPlan over the staged pipeline (stages only, no science): the plan is a job like the others — watched by
stage with its counts, answered in `JobPublic.plan`, another key's to nobody else, its bad fields named."""

from __future__ import annotations

import grpc
import pytest

from manifoundation.contract import JobPublic, PlanRequest
from manifoundation.contract.protos.convert import from_proto, to_proto
from manifoundation.contract.protos.v1 import manifoundation_pb2 as pb

from ..helpers import sphere
from .conftest import HAND, OTHER, Service


def _plan(waypoints: int = 3, **options: object) -> pb.PlanRequest:
    points, normals = sphere(128)
    request = PlanRequest.model_validate({
        "object": {"points": points, "normals": normals}, "start": {"position": [0, 0, 0.1]},
        "waypoints": [{"position": [0.05 * (i + 1), 0, 0.1]} for i in range(waypoints)], "robot": {"name": HAND},
        "options": options,
    })  # fmt: skip
    return to_proto(request, pb.PlanRequest)


def test_submit_plan_is_watched_by_stage_and_answered_in_plan(service: Service) -> None:
    created = service.stub.SubmitPlan(_plan(3), metadata=service.auth())
    updates = list(service.stub.WatchJob(pb.WatchJobRequest(id=created.id), metadata=service.auth(), timeout=30))
    counted = [(u.progress.stage, u.progress.completed, u.progress.total) for u in updates[:-1]
               if u.progress.HasField("total")]  # fmt: skip
    # polled every 0.05 s: any count (even a whole stage) may pass unseen, so what is asserted is that the counts seen
    # are the plan's (3 waypoints to plan), in the pipeline's stage order, never going back
    order = ["repair", "planning", "contacts"]
    assert counted and {stage for stage, _, _ in counted} <= set(order), counted
    assert [order.index(stage) for stage, _, _ in counted] == sorted(order.index(stage) for stage, _, _ in counted)
    planned = [(completed, total) for stage, completed, total in counted if stage == "planning"]
    assert all(total == 3 and 0 <= completed <= 3 for completed, total in planned), counted
    assert planned == sorted(planned), counted
    job = from_proto(updates[-1], JobPublic, answer=True)
    assert job.kind == "plan" and job.state == "succeeded" and job.result is None and job.plan is not None
    assert job.plan.positions.shape == (4, 3) and job.plan.waypoint_indices == [1, 2, 3]
    with pytest.raises(grpc.RpcError) as caught:
        service.stub.GetJob(pb.GetJobRequest(id=created.id), metadata=service.auth(OTHER))
    assert caught.value.code() is grpc.StatusCode.NOT_FOUND


def test_submit_plan_names_the_bad_field(service: Service) -> None:
    message = _plan(1)
    message.waypoints[0].quaternion[:] = [0, 0, 0, 0]
    with pytest.raises(grpc.RpcError) as caught:
        service.stub.SubmitPlan(message, metadata=service.auth())
    assert caught.value.code() is grpc.StatusCode.INVALID_ARGUMENT
    assert "waypoints.0.quaternion" in (caught.value.details() or "")
