"""Error bodies and state rules shared by both backends and the worker side (torch-free).

A job's outcome is a `SynthesisResult` (a plan job's: a `PlanResult`) or an `ErrorBody`; the error's `ErrorType`
decides the terminal state (`ErrorType.job_state`): ``Cancelled`` → cancelled, ``DeadlineExceeded`` /
``ResultExpired`` → expired, anything else → failed.
"""

from __future__ import annotations

import uuid
from typing import Any

from manifoundation.contract import (
    ErrorBody,
    ErrorType,
    JobKind,
    JobPublic,
    JobState,
    PlanResult,
    RobotPublic,
    SynthesisResult,
)
from manifoundation.contract.codec import unpack
from manifoundation.server.queue.base import QueueUnavailable, RobotDeadlineExceeded, RobotInvalid

REGISTRATION_GRACE_S = 3.0
"""Seconds the service waits for a worker's answer beyond a registration's deadline: the worker answers at the
deadline (`manifoundation.server.worker.overrun`), or its hard stop ends it a second later."""
STILL_LOADING = "the robot was still loading: the worker loading it was stopped and replaced"
NO_ANSWER = "no worker answered by then (a worker still loading the robot is stopped and replaced)"


def state_for_error(error: ErrorBody) -> JobState:
    """The terminal state a job ends in when its outcome is ``error`` (failed for a type this version does not
    know)."""
    kind = error.kind
    return kind.job_state if kind is not None else JobState.FAILED


def with_answer(job: JobPublic, raw: bytes | None) -> JobPublic:
    """``job`` with its stored answer (msgpack bytes, None: none) validated as its kind's: ``result`` for a
    synthesis, ``plan`` for a plan. The one validation of an answer on the service side."""
    if raw is not None and job.kind is JobKind.PLAN:
        job.plan = PlanResult.model_validate(unpack(raw))
    elif raw is not None:
        job.result = SynthesisResult.model_validate(unpack(raw))
    return job


def cancelled_error() -> ErrorBody:
    return ErrorBody.of(ErrorType.CANCELLED, "job cancelled")


def deadline_error(stage: str = "before it started") -> ErrorBody:
    return ErrorBody.of(ErrorType.DEADLINE_EXCEEDED, f"job deadline passed {stage}")


def result_expired_error() -> ErrorBody:
    return ErrorBody.of(ErrorType.RESULT_EXPIRED, "the job finished but its result expired and was removed")


def shutdown_error(detail: str = "queue shut down") -> ErrorBody:
    return ErrorBody.of(ErrorType.QUEUE_SHUTDOWN, detail)


def worker_lost_error(detail: str, delivery: int, max_deliveries: int) -> ErrorBody:
    return ErrorBody.of(ErrorType.WORKER_LOST, f"{detail} (delivery {delivery} of {max_deliveries})")


def robot_reply(reply: dict[str, Any], timeout: float) -> RobotPublic:
    """The robot a worker's answer to a registration holds (``robot``), or the queue error its ``error`` stands
    for (``type``: ``DeadlineExceeded``, ``Unavailable``; anything else: the description was refused)."""
    if "error" not in reply:
        return RobotPublic.model_validate(reply["robot"])
    message, kind = str(reply["error"]), reply.get("type")
    if kind == ErrorType.DEADLINE_EXCEEDED.value:
        raise RobotDeadlineExceeded(registration_overrun(timeout, message))
    if kind == ErrorType.UNAVAILABLE.value:
        raise QueueUnavailable(message)
    raise RobotInvalid(message)


def registration_overrun(timeout: float, what: str = STILL_LOADING) -> str:
    """The message of a registration stopped at its deadline."""
    return f"registration deadline of {timeout:g} s passed (MANI_ROBOT_REGISTER_TIMEOUT): {what}"


def new_id() -> str:
    """A job / batch / worker id: 32 hex characters."""
    return uuid.uuid4().hex


def scoped_robot(owner: str | None, name: str) -> str:
    """The key of a registered robot in its owner's namespace (hand names never contain "/")."""
    return f"{owner}/{name}" if owner else name
