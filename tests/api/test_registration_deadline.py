"""A registration still loading at MANI_ROBOT_REGISTER_TIMEOUT is answered as such at every front end (HTTP 504,
gRPC DEADLINE_EXCEEDED, both ``DeadlineExceeded`` naming the deadline), and the service goes on with a fresh worker.
The mechanism itself (the worker stopped and replaced, a job beside it on time):
tests/worker/test_registration_deadline.py."""

from __future__ import annotations

import time

import grpc
import httpx
import pytest

from manifoundation.contract.protos.v1 import manifoundation_pb2 as pb
from manifoundation.contract.protos.v1 import manifoundation_pb2_grpc as pb_grpc
from manifoundation.server.api.app import create_app
from manifoundation.server.api.grpc.errors import ERROR_KEY
from manifoundation.server.api.settings import Settings

from .server import free_port, serving
from .workers import start_queue_and_workers

URDF = '<robot name="r"><link name="a"/><link name="b"/><joint name="j" type="revolute"><parent link="a"/>' \
       '<child link="b"/><limit lower="0" upper="1"/></joint></robot>'  # fmt: skip
MESSAGE = "registration deadline of 1.5 s passed (MANI_ROBOT_REGISTER_TIMEOUT): the robot was still loading"


def ready(http: httpx.Client) -> None:
    end = time.monotonic() + 60
    while http.get("/readyz").status_code != 200:
        assert time.monotonic() < end, "no worker became ready"
        time.sleep(0.05)


def test_http_and_grpc_answer_the_deadline(request: pytest.FixtureRequest) -> None:
    with start_queue_and_workers(request, slow_robot="slow", robot_seconds=60.0) as queue:
        port = free_port()
        settings = Settings(rate_limit_per_s=0, robots_cache_s=0, robot_register_timeout=1.5, grpc_port=port)
        with (
            serving(create_app(settings, queue=queue, grpc=True)) as base,
            httpx.Client(base_url=base, timeout=30) as http,
            grpc.insecure_channel(f"127.0.0.1:{port}") as channel,
        ):
            ready(http)
            answer = http.post("/v1/robots", json={"name": "slow", "urdf": URDF, "fingertips": ["b"]})
            assert answer.status_code == 504, answer.text
            assert answer.json()["type"] == "DeadlineExceeded" and answer.json()["error"].startswith(MESSAGE)
            ready(http)  # a fresh worker in its place
            stub = pb_grpc.ManiFoundationStub(channel)
            with pytest.raises(grpc.RpcError) as failed:
                stub.RegisterRobot(pb.RobotRegister(name="slow", urdf=URDF, fingertips=["b"]), timeout=30)
            assert failed.value.code() is grpc.StatusCode.DEADLINE_EXCEEDED
            body = pb.ErrorBody.FromString(dict(failed.value.trailing_metadata())[ERROR_KEY])
            assert body.type == "DeadlineExceeded" and body.error.startswith(MESSAGE)
            ready(http)
            quick = http.post("/v1/robots", json={"name": "quick", "urdf": URDF, "fingertips": ["b"]})
            assert quick.status_code == 201, quick.text
