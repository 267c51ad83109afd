"""The real models pipeline behind the queue: wire ↔ science conversion, and round trips through both backends
(given contacts and the direct-grasp baseline run end to end; the network method fails clearly without weights).
The conversion (`manifoundation.server.worker.convert`) runs inside the worker processes here, on these small real
requests."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from manifoundation.contract import JobState, Method, SynthesisRequest
from manifoundation.server.queue import create_queue

from .helpers import live_workers, redis_workers, run

MODELS = "manifoundation.server.worker.models_pipeline:ModelsPipeline"
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


@pytest.mark.parametrize("backend", ["embedded", pytest.param("redis", marks=pytest.mark.slow)])
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
    from manifoundation.server.queue import JobQueue

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
        assert proposal.quality.reason and proposal.history is not None  # return_history honoured
        assert np.allclose(np.abs(proposal.contact_points[:, 0]), 0.03, atol=0.01)  # at the given contacts
        assert {"initialisation", "refinement", "verification"} <= set(given.result.timings)
        assert baseline.state is JobState.SUCCEEDED and baseline.result and baseline.result.proposals
        assert network.state is JobState.FAILED and network.error and network.error.type == "ModelUnavailable"
        assert "trained model" in network.error.error
    finally:
        await queue.close()


def test_a_model_refuses_materials_it_was_not_trained_on(tmp_path: Path) -> None:
    import json
    import shutil

    import manifoundation.core
    from manifoundation.server.worker.models_pipeline import ModelsPipeline
    from manifoundation.server.worker.pipeline import JobInput

    # the shipped weights with a card that says rigid and articulated objects only
    shipped = next(p.parent for p in (Path(manifoundation.core.__file__).parent / "weights").glob("*/model_card.json"))
    rigid_only = tmp_path / "rigid_only"
    shutil.copytree(shipped, rigid_only)
    card = json.loads((rigid_only / "model_card.json").read_text())
    card["materials"] = ["rigid", "articulated"]
    (rigid_only / "model_card.json").write_text(json.dumps(card))
    pipeline = ModelsPipeline(hands=["panda_gripper"], weights_dir=str(rigid_only))
    assert pipeline.model_loaded and pipeline.predictor is not None
    trained_on = pipeline.predictor.card.materials
    cloth = make_request("network", object={
        "points": make_request("network").object.points, "material": "cloth", "properties": {"friction": 0.8},
    })  # fmt: skip
    [outcome] = pipeline.run([JobInput(id="cloth", request=cloth)], lambda *a: None, lambda job_id: False)
    assert "cloth" not in trained_on
    assert getattr(outcome, "type", None) == "ValidationError"
    assert "object.material: 'cloth' is not supported" in outcome.error  # type: ignore[union-attr]
    # The baseline needs no network, so the same object is served with it.
    [baseline] = pipeline.run(
        [JobInput(id="b", request=cloth.model_copy(update={"options": cloth.options.model_copy(
            update={"method": Method.DIRECT_GRASP})}))],
        lambda *a: None, lambda job_id: False,
    )  # fmt: skip
    assert getattr(baseline, "proposals", None)


def test_an_unknown_hand_is_a_404_naming_the_field() -> None:
    from manifoundation.contract import ErrorBody, ErrorType
    from manifoundation.server.worker.models_pipeline import ModelsPipeline
    from manifoundation.server.worker.pipeline import JobInput

    pipeline = ModelsPipeline(hands=["panda_gripper"], weights_dir=NO_WEIGHTS)
    request = make_request("contacts", robot={"name": "no_such_hand"}, contacts=CONTACTS)
    [outcome] = pipeline.run([JobInput(id="u", request=request)], lambda *a: None, lambda job_id: False)
    assert isinstance(outcome, ErrorBody) and outcome.kind is ErrorType.UNKNOWN_HAND and outcome.status == 404
    assert outcome.error.startswith("robot.name:")


@pytest.mark.parametrize("keep", [True, False])
def test_a_worker_prepares_an_object_it_has_seen_once_unless_told_not_to(keep: bool) -> None:
    from manifoundation.server.worker.models_pipeline import ModelsPipeline
    from manifoundation.server.worker.pipeline import JobInput

    pipeline = ModelsPipeline(hands=["panda_gripper"], weights_dir=NO_WEIGHTS, object_cache=keep)
    request = make_request("contacts", contacts=CONTACTS)
    first, again = (pipeline.run([JobInput(id=i, request=request)], lambda *a: None, lambda job_id: False)[0]
                    for i in ("a", "b"))  # fmt: skip
    assert pipeline.objects.objects.hits == (1 if keep else 0) and len(pipeline.objects.objects) == int(keep)
    timing = {"quality": {"physics": {"seconds"}}}  # the simulated test's wall time differs from run to run
    assert [p.model_dump_json(exclude=timing) for p in first.proposals] == [
        p.model_dump_json(exclude=timing) for p in again.proposals
    ]
