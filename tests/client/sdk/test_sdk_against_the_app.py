"""The SDK (`manifoundation.sdk`) against this service: the two sides of the wire agree (JSON and msgpack)."""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np
import pytest

from manifoundation.contract import ErrorBody
from manifoundation.sdk import Client, JobFailed, NotFound, Unauthorized
from manifoundation.server.api.app import create_app
from manifoundation.server.api.settings import Settings
from tests.api.fakes import FakeQueue
from tests.api.helpers import sphere
from tests.api.server import serving

KEY = "sdk-test-key-12"


@pytest.fixture(scope="module")
def served() -> Iterator[tuple[str, FakeQueue]]:
    queue = FakeQueue()
    with serving(create_app(Settings(api_keys=[KEY], sync_wait_max=2), queue=queue)) as base:
        yield base, queue


def test_sdk_round_trips(served: tuple[str, FakeQueue]) -> None:
    base, queue = served
    points, normals = sphere(128)
    obj = np.hstack([points, normals])
    with Client(base, KEY) as client:
        result = client.synthesize(obj, "force_closure", "fake_hand", method="direct_grasp", return_heatmap=True)
        assert result.proposals and result.heatmap is not None
        job = client.submit(obj, "force_closure", "fake_hand", method="direct_grasp")
        assert job.status().state == "succeeded"
        assert [r.name for r in client.robots()] == ["fake_hand"]
        with pytest.raises(NotFound):
            client.synthesize(obj, "force_closure", "no_such_hand", method="direct_grasp")
        queue.hold = True
        try:
            job = client.submit(obj, "force_closure", "fake_hand", method="direct_grasp")
            queue.finish(job.id, ErrorBody(error="boom", type="ValidationError"))
            assert job.status().state == "failed"
        finally:
            queue.hold = False
    with Client(base, "wrong-key-123") as client, pytest.raises(Unauthorized):
        client.robots()


def test_sdk_sees_job_failures(served: tuple[str, FakeQueue]) -> None:
    base, queue = served
    points, normals = sphere(128)
    original = queue.finish

    def failing(job_id: str, error: ErrorBody | None = None) -> None:
        original(job_id, error or ErrorBody(error="object.points: degenerate", type="ValidationError"))

    queue.finish = failing  # type: ignore[method-assign]
    try:
        with Client(base, KEY) as client, pytest.raises(JobFailed):
            client.synthesize(np.hstack([points, normals]), "force_closure", "fake_hand", method="direct_grasp")
    finally:
        queue.finish = original  # type: ignore[method-assign]
