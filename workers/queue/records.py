"""Error types and state rules shared by both backends and the worker side (torch-free).

A job's outcome is a `SynthesisResult` or an `ErrorBody`; the error's ``type`` decides the terminal state:
``Cancelled`` → cancelled, ``DeadlineExceeded`` / ``ResultExpired`` → expired, anything else → failed.
"""

from __future__ import annotations

import uuid

from clients.schemas import ErrorBody, JobState

CANCELLED = "Cancelled"
DEADLINE_EXCEEDED = "DeadlineExceeded"
RESULT_EXPIRED = "ResultExpired"
WORKER_LOST = "WorkerLost"
SHUTDOWN = "QueueShutdown"
MODEL_UNAVAILABLE = "ModelUnavailable"


def state_for_error(error: ErrorBody) -> JobState:
    """The terminal state a job ends in when its outcome is ``error``."""
    if error.type == CANCELLED:
        return JobState.CANCELLED
    if error.type in (DEADLINE_EXCEEDED, RESULT_EXPIRED):
        return JobState.EXPIRED
    return JobState.FAILED


def cancelled_error() -> ErrorBody:
    return ErrorBody(error="job cancelled", type=CANCELLED)


def deadline_error(stage: str = "before it started") -> ErrorBody:
    return ErrorBody(error=f"job deadline passed {stage}", type=DEADLINE_EXCEEDED)


def result_expired_error() -> ErrorBody:
    return ErrorBody(error="the job finished but its result expired and was removed", type=RESULT_EXPIRED)


def worker_lost_error(detail: str, delivery: int, max_deliveries: int) -> ErrorBody:
    return ErrorBody(
        error=f"{detail} (delivery {delivery} of {max_deliveries})",
        type=WORKER_LOST,
    )


def new_id() -> str:
    """A job / batch / worker id: 32 hex characters."""
    return uuid.uuid4().hex


def scoped_robot(owner: str | None, name: str) -> str:
    """The key of a registered robot in its owner's namespace (hand names never contain "/")."""
    return f"{owner}/{name}" if owner else name
