"""Readiness over grpc.health.v1 follows /readyz's meaning as the queue comes and goes; liveness stays up."""

from __future__ import annotations

import time

import grpc
from grpc_health.v1 import health_pb2, health_pb2_grpc

from manifoundation.server.api.app import create_app
from manifoundation.server.api.settings import Settings

from ..fakes import FakeQueue
from ..server import free_port, serving

SERVING, NOT_SERVING = health_pb2.HealthCheckResponse.SERVING, health_pb2.HealthCheckResponse.NOT_SERVING


def _status_becomes(health: health_pb2_grpc.HealthStub, service: str, wanted: int) -> None:
    end = time.monotonic() + 5
    while (status := health.Check(health_pb2.HealthCheckRequest(service=service)).status) != wanted:
        assert time.monotonic() < end, f"{service!r} stayed {status}"
        time.sleep(0.05)


def test_readiness_follows_the_queue() -> None:
    queue = FakeQueue()
    port = free_port()
    settings = Settings(grpc_port=port, grpc_health_interval=0.1)
    with serving(create_app(settings, queue=queue, grpc=True)), grpc.insecure_channel(f"127.0.0.1:{port}") as channel:  # type: ignore[arg-type]
        health = health_pb2_grpc.HealthStub(channel)
        name = "manifoundation.v1.ManiFoundation"
        _status_becomes(health, name, SERVING)
        queue.down = True
        _status_becomes(health, name, NOT_SERVING)
        assert health.Check(health_pb2.HealthCheckRequest(service="")).status == SERVING
        queue.down = False
        _status_becomes(health, name, SERVING)
