"""The plan wire schemas (draft for POST /v1/plans): defaults, field-naming errors, JSON and msgpack round trips."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from pydantic import ValidationError

from manifoundation.contract.codec import dump_model, load_model
from manifoundation.contract.plans import PlanRequest, PlanResult
from manifoundation.contract.validation import field_errors

POINTS = np.random.default_rng(2).normal(size=(80, 3)) * 0.03


def _body(**overrides: Any) -> dict[str, Any]:
    body: dict[str, Any] = {
        "object": {"points": POINTS},
        "start": {"position": [0, 0, 0]},
        "waypoints": [{"position": [0, 0, 0.1]}, {"position": [0.2, 0, 0.1], "quaternion": [2, 0, 0, 0]}],
        "scene": {"support_plane": {"height": 0.0}, "obstacles": [
            {"kind": "box", "name": "wall", "size": [0.02, 0.4, 0.3], "pose": {"position": [0.1, 0, 0.15]}},
            {"kind": "points", "points": np.zeros((5, 3)), "resolution": 0.02},
        ]},
        "robot": {"name": "allegro"},
    }  # fmt: skip
    body.update(overrides)
    return body


def _errors(body: dict[str, Any]) -> list[tuple[str, str]]:
    with pytest.raises(ValidationError) as info:
        PlanRequest.model_validate(body)
    return [(e.field, e.problem) for e in field_errors(info.value)]


def test_defaults_and_normalised_quaternions() -> None:
    req = PlanRequest.model_validate(_body())
    assert req.options.time_limit == 5.0 and req.options.repair == "nearest" and req.options.method == "network"
    np.testing.assert_allclose(req.waypoints[1].quaternion, [1, 0, 0, 0])
    np.testing.assert_allclose(req.start.quaternion, [1, 0, 0, 0])
    assert [o.kind for o in req.scene.obstacles] == ["box", "points"]


def test_bad_fields_are_named() -> None:
    (field, _), = _errors(_body(waypoints=[]))
    assert field == "waypoints"
    bad_box = {"obstacles": [{"kind": "box", "size": [0.1, 0, 0.1]}]}
    assert _errors(_body(scene=bad_box))[0][0].startswith("scene.obstacles.0")
    assert _errors(_body(options={"translation_step": 0}))[0][0] == "options.translation_step"
    assert _errors(_body(options={"repair": "ignore"}))[0][0] == "options.repair"
    (field, problem), = _errors(_body(object={"points": POINTS, "material": "cloth"}))
    assert "rigidly" in problem


def test_result_round_trips_in_json_and_msgpack() -> None:
    result = PlanResult(success=True, positions=np.zeros((3, 3)), quaternions=np.tile([1.0, 0, 0, 0], (3, 1)),
                        waypoint_indices=[2], hand="allegro")  # fmt: skip
    again = PlanResult.model_validate_json(result.model_dump_json())
    np.testing.assert_array_equal(again.quaternions, result.quaternions)
    back = load_model(PlanResult, dump_model(result, "application/msgpack"), "application/msgpack")
    assert back.positions.dtype == np.float64 and back.positions.shape == (3, 3)
    with pytest.raises(ValidationError, match="one per position"):
        PlanResult(success=True, positions=np.zeros((3, 3)), quaternions=np.zeros((2, 4)), waypoint_indices=[],
                   hand="x")  # fmt: skip
