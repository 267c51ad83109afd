"""Validation of whole requests: cross-field shapes, tasks, robots, options."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from pydantic import ValidationError

from manifoundation.contract import BatchCreate, DeltaPoseTask, SynthesisRequest
from manifoundation.contract.validation import field_errors, summary

POINTS = np.random.default_rng(2).normal(size=(80, 3))


def _body(**overrides: Any) -> dict[str, Any]:
    body: dict[str, Any] = {"object": {"points": POINTS}, "task": {"kind": "force_closure"}, "robot": {"name": "leap"}}
    body.update(overrides)
    return body


def _errors(body: dict[str, Any]) -> list[tuple[str, str]]:
    with pytest.raises(ValidationError) as info:
        SynthesisRequest.model_validate(body)
    return [(e.field, e.problem) for e in field_errors(info.value)]


def test_minimal_request_has_defaults() -> None:
    request = SynthesisRequest.model_validate(_body())
    assert request.options.max_iterations == 100 and request.options.refine


def test_motion_must_match_points() -> None:
    assert _errors(_body(task={"kind": "point_motion", "motion": np.zeros((79, 3))})) == [
        ("task.motion", "shape (79, 3) does not match points (80, 3)")
    ]


def test_targets_must_match_points() -> None:
    [(field, _)] = _errors(_body(task={"kind": "target_points", "targets": np.zeros((81, 3))}))
    assert field == "task.targets"


def test_wrench_nan_names_the_field() -> None:
    [(field, problem)] = _errors(_body(task={"kind": "wrench", "wrench": [0, 0, 1, 0, 0, np.nan]}))
    assert field == "task.wrench" and "NaN" in problem


def test_zero_norm_quaternion() -> None:
    [(field, problem)] = _errors(_body(task={"kind": "delta_pose", "rotation": [0, 0, 0, 0]}))
    assert field == "task.rotation" and problem == "quaternion has zero norm"


@given(st.lists(st.floats(-1, 1), min_size=4, max_size=4).filter(lambda q: np.linalg.norm(q) > 1e-3))
def test_quaternions_are_normalised(q: list[float]) -> None:
    task = DeltaPoseTask(translation=[0.01, 0, 0], rotation=q)
    assert abs(np.linalg.norm(task.rotation) - 1) < 1e-12


def test_identity_delta_pose_is_refused() -> None:
    assert _errors(_body(task={"kind": "delta_pose"}))[0][0] == "task"


def test_unknown_task_kind() -> None:
    [(field, problem)] = _errors(_body(task={"kind": "teleport"}))
    assert field == "task" and "teleport" in problem


def test_robot_needs_exactly_one_source() -> None:
    assert _errors(_body(robot={}))[0] == ("robot", "give exactly one of 'name' or 'urdf'")
    assert _errors(_body(robot={"urdf": "<robot/>"}))[0] == ("robot.fingertips", "required with an inline urdf")
    assert _errors(_body(robot={"name": "Bad Name!"}))[0][0] == "robot.name"


def test_contacts_method_needs_contacts() -> None:
    assert _errors(_body(options={"method": "contacts"})) == [("contacts", "required with options.method 'contacts'")]
    request = SynthesisRequest.model_validate(_body(options={"method": "contacts"}, contacts={"points": POINTS[:3]}))
    assert request.contacts is not None and request.contacts.points.shape == (3, 3)


def test_joint_motion_needs_articulated_object() -> None:
    assert _errors(_body(task={"kind": "joint_motion", "delta": 0.3}))[0] == (
        "task",
        "joint_motion needs an articulated object",
    )


@pytest.mark.parametrize(("option", "value"), [("num_proposals", 0), ("max_iterations", 501), ("timeout", 0)])
def test_option_ranges(option: str, value: int) -> None:
    assert _errors(_body(options={option: value}))[0][0] == f"options.{option}"


def test_batch_errors_carry_the_item_index() -> None:
    good = _body()
    bad = _body(object={"points": POINTS[:10]})
    with pytest.raises(ValidationError) as info:
        BatchCreate.model_validate({"requests": [good, bad]})
    errors = field_errors(info.value)
    assert errors[0].field == "requests.1.object.points"
    assert summary(errors).startswith("requests.1.object.points: 10 points given")


def test_given_contacts_carry_points_only() -> None:
    contacts = {"points": POINTS[:2], "forces": np.ones((2, 3))}
    assert [f for f, _ in _errors(_body(contacts=contacts))] == ["contacts.forces"]
    assert SynthesisRequest.model_validate(_body(contacts={"points": POINTS[:2]})).contacts is not None


def test_stop_after_verified_within_the_proposals() -> None:
    assert _errors(_body(options={"num_proposals": 2, "stop_after_verified": 3})) == [
        ("options.stop_after_verified", "3 is more than num_proposals (2): it could never stop early")
    ]
    assert _errors(_body(options={"stop_after_verified": 0}))[0][0] == "options.stop_after_verified"
    request = SynthesisRequest.model_validate(_body(options={"num_proposals": 4, "stop_after_verified": 1}))
    assert request.options.stop_after_verified == 1


def test_rollout_corrections_need_the_rollout_and_stay_bounded() -> None:
    assert _errors(_body(options={"rollout_corrections": 3})) == [
        ("options.rollout_corrections", "3 needs simulate_rollout: the corrections are rollouts")
    ]
    assert _errors(_body(options={"simulate_rollout": True, "rollout_corrections": 9}))[0][0] == \
        "options.rollout_corrections"
    request = SynthesisRequest.model_validate(_body(options={"simulate_rollout": True, "rollout_corrections": 4}))
    assert request.options.rollout_corrections == 4
