"""One real service for the gRPC tests: the FastAPI app with gRPC on a free port (same process, same queue),
embedded workers running `research.staged_pipeline.StagedPipeline` (0.05 s a stage: a job of ``max_iterations`` k takes
about (k + 3) × 0.05 s)."""

from __future__ import annotations

import contextlib
import time
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any

import grpc
import httpx
import pytest
from fastapi import FastAPI
from grpc_health.v1 import health_pb2, health_pb2_grpc

from manifoundation.contract import SynthesisRequest
from manifoundation.contract.protos.convert import to_proto
from manifoundation.contract.protos.v1 import manifoundation_pb2 as pb
from manifoundation.contract.protos.v1 import manifoundation_pb2_grpc as pb_grpc
from manifoundation.server.api.app import create_app
from manifoundation.server.api.grpc.server import SERVICE_NAME
from manifoundation.server.api.settings import Settings

from ..helpers import request_body
from ..server import free_port, serving
from ..workers import start_queue_and_workers

KEY, OTHER = "grpc-test-key-1", "grpc-test-key-2"
HAND = "test_gripper"
LIMIT = 64 * 1024 * 1024
FAIL_SEED = 666  # a request with this seed makes the staged pipeline raise


@dataclass
class Service:
    app: FastAPI
    base: str
    target: str
    channel: grpc.Channel
    stub: pb_grpc.ManiFoundationStub

    def auth(self, key: str = KEY) -> tuple[tuple[str, str], ...]:
        return (("authorization", f"Bearer {key}"),)


def request(n: int = 128, **options: Any) -> pb.SynthesisRequest:
    """A small force-closure request for the staged pipeline (2 refinement iterations unless told)."""
    return to_proto(
        SynthesisRequest.model_validate(request_body(HAND, n, **{"max_iterations": 2, **options})),
        pb.SynthesisRequest,
    )


@pytest.fixture(scope="package")
def service(request: pytest.FixtureRequest) -> Iterator[Service]:
    """The service on the embedded backend, shared by the package's tests."""
    with running(request) as svc:
        yield svc


@pytest.fixture(scope="module", params=["redis"])
def redis_service(request: pytest.FixtureRequest) -> Iterator[Service]:
    """The service in front of Redis Streams, a `mani worker` process behind it (skipped without Redis)."""
    with running(request) as svc:
        yield svc


@contextlib.contextmanager
def running(request: pytest.FixtureRequest) -> Iterator[Service]:
    """The app with gRPC on a free port, over the backend ``request.param`` names (default: embedded)."""
    with start_queue_and_workers(request, stage_seconds=0.05, iterations=20, max_queue=8, fail_seed=FAIL_SEED) as queue:
        port = free_port()
        settings = Settings(
            api_keys=[KEY, OTHER], rate_limit_per_s=0, grpc_port=port, sse_interval=0.05, grpc_health_interval=0.2
        )
        app = create_app(settings, queue=queue, grpc=True)
        with serving(app) as base:
            options = [("grpc.max_receive_message_length", LIMIT), ("grpc.max_send_message_length", -1)]
            channel = grpc.insecure_channel(f"127.0.0.1:{port}", options=options)
            health = health_pb2_grpc.HealthStub(channel)
            deadline = time.monotonic() + 120
            while health.Check(health_pb2.HealthCheckRequest(service=SERVICE_NAME)).status != 1:
                assert time.monotonic() < deadline, "no worker became ready"
                time.sleep(0.1)
            yield Service(app, base, f"127.0.0.1:{port}", channel, pb_grpc.ManiFoundationStub(channel))
            channel.close()


def wait_terminal(service: Service, job_id: str, timeout: float = 20.0) -> pb.JobPublic:
    """Poll GetJob until the job ends."""
    end = time.monotonic() + timeout
    while True:
        job = service.stub.GetJob(pb.GetJobRequest(id=job_id), metadata=service.auth())
        if job.state in ("succeeded", "failed", "cancelled", "expired") or time.monotonic() > end:
            return job
        time.sleep(0.05)


def metrics_text(service: Service) -> str:
    return httpx.get(f"{service.base}/metrics", headers={"Authorization": f"Bearer {KEY}"}).text


def calls_ok(service: Service, method: str) -> int:
    """How many calls of the RPC ``method`` ended OK (the service's own counter)."""
    line = f'mani_grpc_requests_total{{code="OK",method="{method}"}} '
    rows = metrics_text(service).splitlines()
    return next((int(float(row[len(line) :])) for row in rows if row.startswith(line)), 0)
