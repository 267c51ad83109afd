"""The real models pipeline behind the queue: wire ↔ science conversion, and round trips through both backends
(given contacts and the direct-grasp baseline run end to end; the network method fails clearly without weights)."""

from __future__ import annotations

import time

import numpy as np
import pytest

from clients.schemas import JobState, SynthesisRequest
from workers.queue import create_queue

from .helpers import live_workers, redis_workers, run

MODELS = "workers.models_pipeline:ModelsPipeline"
OPTIONS = {"hands": ["panda_gripper"]}
NO_WEIGHTS = "/nonexistent-weights"


def make_request(method: str, **extra: object) -> SynthesisRequest:
    rng = np.random.default_rng(0)
    normals = rng.normal(size=(256, 3))
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    body: dict[str, object] = {
        "object": {"points": 0.03 * normals, "normals": normals, "properties": {"friction": 0.8}},
        "task": {"kind": "force_closure"},
        "robot": {"name": "panda_gripper"},
        "options": {"method": method, "max_iterations": 30, "return_history": True},
    }
    return SynthesisRequest.model_validate(body | extra)


CONTACTS = {"points": 0.03 * np.array([[1.0, 0.0, 0.0], [-1.0, 0.0, 0.0]])}


def test_convert_request_to_core_input_and_back() -> None:
    from models.pipeline import SynthesisInput
    from models.robots import get_hand
    from workers.convert import method_of, to_input

    hand = get_hand("panda_gripper")
    req = make_request("auto", contacts=CONTACTS, task={"kind": "wrench", "wrench": [0, 0, 1.0, 0, 0, 0]})
    assert method_of(req) == "contacts" and method_of(make_request("auto")) == "network"
    inp = to_input(req, hand, deadline=time.time() + 10)
    assert isinstance(inp, SynthesisInput) and inp.method == "contacts" and inp.hand is hand
    assert inp.task.kind == "wrench" and np.allclose(inp.task.wrench, [0, 0, 1, 0, 0, 0])
    assert inp.properties == {"friction": 0.8} and inp.contacts.shape == (2, 3)
    assert inp.deadline is not None and 9 < inp.deadline - time.monotonic() <= 10


@pytest.mark.parametrize("backend", ["embedded", "redis"])
def test_round_trip_with_the_models_pipeline(backend: str, request: pytest.FixtureRequest) -> None:
    async def main() -> None:
        settings = {"pipeline": MODELS, "pipeline_options": OPTIONS, "weights_dir": NO_WEIGHTS}
        if backend == "embedded":
            queue = create_queue(None, redis_url=None, concurrency=1, start_timeout=120, **settings)
            await queue.start()
            await _exercise(queue)
            return
        url, prefix = request.getfixturevalue("redis_url"), request.getfixturevalue("redis_prefix")
        queue = create_queue(url, queue_prefix=prefix)
        await queue.start()
        with redis_workers(url, prefix, **settings):
            await live_workers(queue, 1, timeout=120)
            await _exercise(queue)

    run(main())


async def _exercise(queue: object) -> None:
    from workers.queue import JobQueue

    assert isinstance(queue, JobQueue)
    try:
        [worker] = await queue.workers()
        assert not worker.model_loaded
        assert [r.name for r in await queue.list_robots()] == ["panda_gripper"]
        ids = await queue.submit(
            [make_request("contacts", contacts=CONTACTS), make_request("direct_grasp"), make_request("network")]
        )
        given, baseline, network = [await queue.wait(i, 120) for i in ids]
        assert given.state is JobState.SUCCEEDED and given.result is not None, given.error
        [proposal] = given.result.proposals
        assert proposal.joint_names == ["panda_finger_joint1"] and proposal.contact_points.shape == (2, 3)
        assert proposal.quality.iterations >= 1 and proposal.history is not None
        assert {"initialisation", "refinement", "verification"} <= set(given.result.timings)
        assert baseline.state is JobState.SUCCEEDED and baseline.result and baseline.result.proposals
        assert network.state is JobState.FAILED and network.error and network.error.type == "ModelUnavailable"
        assert "trained model" in network.error.error
    finally:
        await queue.close()
