"""One real service with the science behind it, for the plan and MCP tests: the FastAPI app with gRPC and the MCP
tools on free ports, API keys on, one worker running `manifoundation.server.worker.models_pipeline.ModelsPipeline`
(Allegro only, no
network weights: the plans use ``random_contacts``, so start-up is torch, the hand and no checkpoint)."""

from __future__ import annotations

import contextlib
import time
from collections.abc import Iterator
from dataclasses import dataclass

import grpc
import httpx
import numpy as np
import pytest

from manifoundation.contract.protos.v1 import manifoundation_pb2_grpc as pb_grpc
from manifoundation.server.api.app import create_app
from manifoundation.server.api.settings import Settings

from .server import free_port, serving
from .workers import start_queue_and_workers

KEY, OTHER = "science-test-key-1", "science-test-key-2"
HAND = "allegro"


@dataclass
class Science:
    base: str
    stub: pb_grpc.ManiFoundationStub

    @staticmethod
    def auth(key: str = KEY) -> dict[str, str]:
        return {"Authorization": f"Bearer {key}"}

    @staticmethod
    def metadata(key: str = KEY) -> tuple[tuple[str, str], ...]:
        return (("authorization", f"Bearer {key}"),)


@contextlib.contextmanager
def science_service(request: pytest.FixtureRequest) -> Iterator[Science]:
    """The service (see module doc) on the backend ``request.param`` names (default: embedded)."""
    options = {"hands": [HAND], "weights_dir": "/nonexistent-weights"}
    with start_queue_and_workers(
        request, pipeline="manifoundation.server.worker.models_pipeline:ModelsPipeline", **options
    ) as queue:
        port = free_port()
        settings = Settings(api_keys=[KEY, OTHER], rate_limit_per_s=0, grpc_port=port, sse_interval=0.05,
                            grpc_grace_s=0)  # fmt: skip
        with serving(create_app(settings, queue=queue, grpc=True)) as base:
            deadline = time.monotonic() + 240
            while not httpx.get(f"{base}/v1/robots", headers=Science.auth(), timeout=10).json()["robots"]:
                assert time.monotonic() < deadline, "no worker published its hands"
                time.sleep(0.2)
            channel = grpc.insecure_channel(f"127.0.0.1:{port}")
            yield Science(base, pb_grpc.ManiFoundationStub(channel))
            channel.close()


def box_object(n: int = 512, size: tuple[float, float, float] = (0.04, 0.06, 0.06)) -> dict[str, object]:
    """A box object (its own frame, centred): ``n`` area-uniform surface points, outward normals, its mesh."""
    import trimesh

    mesh = trimesh.creation.box(extents=size)
    points, faces = trimesh.sample.sample_surface(mesh, n, seed=0)
    return {
        "points": np.asarray(points).tolist(), "normals": np.asarray(mesh.face_normals[faces]).tolist(),
        "mesh": {"vertices": mesh.vertices.tolist(), "faces": mesh.faces.tolist()}, "properties": {"friction": 0.8},
    }  # fmt: skip
