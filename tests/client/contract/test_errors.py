"""The contract's error vocabulary: every type has one status and one terminal state; unknown names degrade."""

from __future__ import annotations

import pytest

from manifoundation.contract import ErrorBody, ErrorType, JobState


@pytest.mark.parametrize("kind", list(ErrorType))
def test_every_type_has_an_error_status_and_a_terminal_state(kind: ErrorType) -> None:
    assert 400 <= kind.status < 600
    assert kind.job_state.terminal and kind.job_state is not JobState.SUCCEEDED


def test_terminal_states_follow_the_type() -> None:
    assert ErrorType.CANCELLED.job_state is JobState.CANCELLED
    assert ErrorType.DEADLINE_EXCEEDED.job_state is JobState.EXPIRED
    assert ErrorType.RESULT_EXPIRED.job_state is JobState.EXPIRED
    assert ErrorType.VALIDATION_ERROR.job_state is JobState.FAILED
    assert ErrorType.UNKNOWN_HAND.status == 404 and ErrorType.INTERNAL_ERROR.status == 500


def test_a_name_this_version_does_not_know_is_kept_and_read_as_a_server_fault() -> None:
    body = ErrorBody.model_validate({"error": "from a newer service", "type": "QuotaExceeded"})
    assert body.type == "QuotaExceeded" and body.kind is None and body.status == 500


def test_bodies_built_from_a_type_carry_its_name() -> None:
    body = ErrorBody.of(ErrorType.QUEUE_FULL, "full")
    assert body.model_dump(exclude_none=True) == {"error": "full", "type": "QueueFull"}
    assert body.kind is ErrorType.QUEUE_FULL and body.status == 429


def test_the_documented_table_is_the_enum() -> None:
    from pathlib import Path

    text = (Path(__file__).resolve().parents[3] / "docs" / "errors.md").read_text()
    rows = {}
    for line in text.splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) == 4 and cells[0].startswith("`"):
            rows[cells[0].strip("`")] = (int(cells[1]), cells[2])
    assert rows == {k.value: (k.status, k.job_state.value) for k in ErrorType}
