"""`POST /v1/plans` end to end with the science in the worker (real OMPL, fcl, refinement, verification), through
HTTP (the SDK), gRPC and the viewer's scene data; errors name the field; one key never sees another's plan."""

from __future__ import annotations

import time

import grpc
import httpx
import numpy as np
import pytest

from manifoundation.contract import JobPublic, PlanRequest
from manifoundation.contract.protos.convert import from_proto, to_proto
from manifoundation.contract.protos.v1 import manifoundation_pb2 as pb
from manifoundation.sdk import Client, JobFailed, box_obstacle, make_plan

from .science import HAND, KEY, OTHER, Science, box_object

WALL = {"kind": "box", "name": "wall", "size": [0.02, 0.4, 0.3], "pose": {"position": [0.0, 0.0, 0.15]}}


def _terminal(science: Science, job_id: str, key: str = KEY, timeout: float = 60.0) -> JobPublic:
    end = time.monotonic() + timeout
    while True:
        job = JobPublic.model_validate(httpx.get(f"{science.base}/v1/jobs/{job_id}", headers=science.auth(key)).json())
        if job.state.terminal or time.monotonic() > end:
            return job
        time.sleep(0.05)


def test_a_held_grasp_is_kept_along_a_pure_translation_and_every_step_is_verified(science: Science) -> None:
    """A 15 cm translation on a table in 5 cm steps: the straight path stays straight (no planner call), the first
    step takes a grasp, the next two keep it with the same contacts on the object, each verified like a single
    request; progress went through the plan's stages; the viewer's scene has the table and the object."""
    start, goal = np.array([-0.075, 0.0, 0.2]), np.array([0.075, 0.0, 0.2])
    plan = make_plan(box_object(), start, [goal], HAND, support_plane=0.0, translation_step=0.05,
                     method="random_contacts", num_proposals=2, seed=1)  # fmt: skip
    with Client(science.base, KEY) as client:
        job = client.submit_plan(plan)
        stages = set()
        while not (status := job.status()).state.terminal:
            stages.add(status.progress.stage.value)
            time.sleep(0.02)
        result = job.plan_result(5)
    assert status.kind == "plan" and "contacts" in stages, stages
    np.testing.assert_allclose(result.positions[:, 0], np.linspace(-0.075, 0.075, 4), atol=1e-9)
    np.testing.assert_allclose(result.positions[:, 1:], [[0.0, 0.2]] * 4, atol=1e-9)
    assert result.segments[0].straight and result.waypoint_indices == [3]
    assert [s.grasp for s in result.steps] == ["new", "kept", "kept"], [(s.grasp, s.dropped) for s in result.steps]
    assert result.success and all(s.proposal is not None and s.proposal.quality.success for s in result.steps)
    first, last = result.steps[0].proposal, result.steps[2].proposal
    assert first is not None and last is not None
    body_first = first.contact_points - result.positions[0]  # identity orientation: body = world - position
    body_last = last.contact_points - result.positions[2]
    np.testing.assert_allclose(body_last, body_first, atol=1e-6)
    assert last.hand_spheres is not None and last.hand_spheres.shape[1] == 4  # the viewer draws the hand
    scene = httpx.get(f"{science.base}/v1/jobs/{job.id}/scene", headers=science.auth()).json()
    assert scene["support_height"] == 0.0 and len(scene["points"]) == 512 and scene["job"]["plan"]["steps"]


def test_a_wall_is_gone_around_over_grpc(science: Science) -> None:
    """The trajectory alone (contacts off) from one side of a wall to the other, submitted with SubmitPlan: the
    straight segment is not free, and at no pose does the placed object (2 000 points sampled on its surface, placed
    by the answered pose with scipy) reach into the wall's box."""
    import trimesh
    from scipy.spatial.transform import Rotation

    request = PlanRequest.model_validate({
        "object": box_object(256), "start": {"position": [-0.1, 0.0, 0.05]},
        "waypoints": [{"position": [0.1, 0.0, 0.05]}], "robot": {"name": HAND},
        "scene": {"obstacles": [WALL], "support_plane": {"height": 0.0}},
        "options": {"contacts": False, "seed": 2, "time_limit": 5.0, "translation_step": 0.01},
    })  # fmt: skip
    created = science.stub.SubmitPlan(to_proto(request, pb.PlanRequest), metadata=science.metadata())
    end = time.monotonic() + 60
    while (message := science.stub.GetJob(pb.GetJobRequest(id=created.id), metadata=science.metadata())).state in (
        "queued", "running") and time.monotonic() < end:  # fmt: skip
        time.sleep(0.05)
    job = from_proto(message, JobPublic, answer=True)
    assert job.kind == "plan" and job.plan is not None, job.error
    plan = job.plan
    np.testing.assert_allclose(plan.positions[[0, -1]], [[-0.1, 0, 0.05], [0.1, 0, 0.05]], atol=1e-9)
    assert not plan.segments[0].straight and not plan.steps
    surface = trimesh.sample.sample_surface(trimesh.creation.box(extents=(0.04, 0.06, 0.06)), 2000, seed=3)[0]
    for position, quaternion in zip(plan.positions, plan.quaternions, strict=True):
        world = Rotation.from_quat(quaternion[[1, 2, 3, 0]]).apply(surface) + position
        inside = (np.abs(world[:, 0]) < 0.01) & (np.abs(world[:, 1]) < 0.2) & (world[:, 2] < 0.3)
        assert not inside.any(), position


def test_errors_name_the_field_and_another_key_sees_nothing(science: Science) -> None:
    """A waypoint inside the wall with repair "report": the job ends InfeasibleWaypoint (422) naming waypoints.0,
    over HTTP and over gRPC; a zero quaternion and 65 waypoints are refused at submission (422 naming the field);
    the other key's reads of the job answer 404."""
    body = {"object": box_object(128), "start": {"position": [-0.1, 0, 0.05]},
            "waypoints": [{"position": [0, 0, 0.1]}], "scene": {"obstacles": [WALL]}, "robot": {"name": HAND},
            "options": {"repair": "report", "contacts": False}}  # fmt: skip
    created = httpx.post(f"{science.base}/v1/plans", json=body, headers=science.auth())
    assert created.status_code == 202, created.text
    job = _terminal(science, created.json()["id"])
    assert job.state == "failed" and job.error is not None and job.error.type == "InfeasibleWaypoint", job.error
    assert job.error.status == 422 and job.error.detail and job.error.detail[0].field == "waypoints.0"
    assert "wall" in job.error.error
    other = httpx.get(f"{science.base}/v1/jobs/{job.id}", headers=science.auth(OTHER))
    assert other.status_code == 404 and other.json()["type"] == "NotFound"
    bad_quaternion = {**body, "waypoints": [{"position": [0, 0, 0.3], "quaternion": [0, 0, 0, 0]}]}
    answer = httpx.post(f"{science.base}/v1/plans", json=bad_quaternion, headers=science.auth())
    assert answer.status_code == 422 and answer.json()["detail"][0]["field"] == "waypoints.0.quaternion"
    too_many = {**body, "waypoints": [{"position": [0, 0, 0.3]}] * 65}
    answer = httpx.post(f"{science.base}/v1/plans", json=too_many, headers=science.auth())
    assert answer.status_code == 422 and answer.json()["detail"][0]["field"] == "waypoints"
    with pytest.raises(grpc.RpcError) as caught:  # the same refusal over gRPC, before a job exists
        science.stub.SubmitPlan(to_proto(PlanRequest.model_validate(body), pb.PlanRequest).__class__(
            start=pb.PoseIn(position=[0, 0, 0]), robot=pb.RobotIn(name=HAND)), metadata=science.metadata())
    assert caught.value.code() is grpc.StatusCode.INVALID_ARGUMENT and "object" in (caught.value.details() or "")


def test_the_sdk_raises_the_typed_job_error(science: Science) -> None:
    """`Client.plan` on a waypoint it may not repair: `JobFailed` carrying InfeasibleWaypoint and its field."""
    with Client(science.base, KEY) as client, pytest.raises(JobFailed) as caught:
        client.plan(box_object(128), [-0.1, 0, 0.05], [[0, 0, 0.1]], HAND, wait=60,
                    obstacles=[box_obstacle([0.02, 0.4, 0.3], [0, 0, 0.15], name="wall")], repair="report")  # fmt: skip
    error = caught.value.error
    assert error is not None and error.type == "InfeasibleWaypoint" and error.detail[0].field == "waypoints.0"


@pytest.mark.slow
def test_the_viewer_plays_the_plan(science: Science) -> None:
    """The job's page in headless Chromium: the plan's table, the slider over its poses, the scene's obstacles."""
    from .browser import chromium, dump_dom

    chromium()
    body = {"object": box_object(128), "start": {"position": [-0.1, 0, 0.05]},
            "waypoints": [{"position": [0.1, 0, 0.05]}], "robot": {"name": HAND},
            "scene": {"obstacles": [WALL], "support_plane": {"height": 0.0}}, "options": {"contacts": False, "seed": 2}}
    job_id = httpx.post(f"{science.base}/v1/plans", json=body, headers=science.auth()).json()["id"]
    job = _terminal(science, job_id)
    assert job.plan is not None
    dom = dump_dom(f"{science.base}/view/{job_id}#key={KEY}")
    assert f"pose 0 of {len(job.plan.positions) - 1}" in dom and "could not load" not in dom
    import re

    legend = re.findall(r'class="legendtext"[^>]*>([^<]*)<', dom)
    assert "main-svg" in dom and {"wall", "support plane", "path"} <= set(legend), legend
