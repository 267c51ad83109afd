"""The small interface between a worker and the science it runs (an engine behind a protocol, docs/layering.md).

A worker hands a `Pipeline` a micro-batch of `JobInput` and gets one outcome per job: a `SynthesisResult`, or an
`ErrorBody` (``type`` "Cancelled" / "DeadlineExceeded" / the error's class). A plan job (`PlanJob`) runs alone
through `Pipeline.plan`: a `PlanResult` or an `ErrorBody`. The default is
`manifoundation.server.worker.models_pipeline.ModelsPipeline` (the `models` pipeline);
`research.staged_pipeline.StagedPipeline` is a small
real pipeline for queue tests and benchmarks (it walks the stages, does no science). Chosen by
``QueueSettings.pipeline`` ("module:attr") with ``pipeline_options`` as keyword arguments. This module is
torch-free; a pipeline imports its heavy dependencies in its own module, in the worker process.
"""

from __future__ import annotations

import importlib
import inspect
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Protocol, runtime_checkable

from manifoundation.contract import (
    ErrorBody,
    ErrorType,
    FieldError,
    PlanRequest,
    PlanResult,
    RobotPublic,
    RobotRegister,
    Stage,
    SynthesisRequest,
    SynthesisResult,
)
from manifoundation.contract.validation import field_errors, summary

Outcome = SynthesisResult | ErrorBody
PlanOutcome = PlanResult | ErrorBody
ProgressFn = Callable[[str, Stage, float, int | None, int | None], None]
"""progress(job_id, stage, fraction, iteration, max_iterations)."""
PlanProgressFn = Callable[[str, Stage, int, int], None]
"""progress(job_id, stage, completed, total): a plan's waypoints checked, segments planned, steps synthesised."""
CancelFn = Callable[[str], bool]
"""should_cancel(job_id): whether the job was cancelled (checked between stages)."""


@dataclass
class JobInput:
    """One job as a pipeline sees it."""

    id: str
    request: SynthesisRequest
    deadline: float | None = None  # unix time; the pipeline stops refining when it passes
    robot: RobotRegister | None = None  # the registered description when the request names a user robot
    request_id: str | None = None  # X-Request-ID of the HTTP request that submitted the job (for the logs)


@dataclass
class PlanJob:
    """One plan job as a pipeline sees it (fields as `JobInput`'s)."""

    id: str
    request: PlanRequest
    deadline: float | None = None
    robot: RobotRegister | None = None
    request_id: str | None = None


@runtime_checkable
class Pipeline(Protocol):
    """What a worker needs from the science."""

    model_loaded: bool
    model_version: str | None

    def robots(self) -> list[RobotPublic]:
        """The built-in hands this pipeline can use (published by the worker at start-up)."""
        ...

    def validate_robot(self, robot: RobotRegister) -> RobotPublic:
        """Load a user's robot with the hardened loader. Raises ValueError with the reason when invalid."""
        ...

    def run(self, jobs: list[JobInput], progress: ProgressFn, should_cancel: CancelFn) -> list[Outcome]:
        """Run a micro-batch; one outcome per job, in order. May raise (the worker isolates the bad job)."""
        ...

    def plan(self, job: PlanJob, progress: PlanProgressFn, should_cancel: CancelFn) -> PlanOutcome:
        """Plan one manipulation (trajectory + contacts per step). May raise (the worker fails the job)."""
        ...


def load_pipeline(spec: str, options: dict[str, Any] | None = None, weights_dir: str | None = None) -> Pipeline:
    """Instantiate ``"module:attr"`` with ``options`` as keyword arguments (plus ``weights_dir`` when given and
    the factory takes it)."""
    module_name, _, attr = spec.partition(":")
    factory = getattr(importlib.import_module(module_name), attr)
    kwargs = dict(options or {})
    if weights_dir and "weights_dir" in inspect.signature(factory).parameters:
        kwargs.setdefault("weights_dir", weights_dir)
    pipeline = factory(**kwargs)
    if not isinstance(pipeline, Pipeline):
        raise TypeError(f"{spec} does not implement manifoundation.server.worker.pipeline.Pipeline")
    return pipeline


def error_from_exception(exc: BaseException) -> ErrorBody:
    """The one translation of an exception into a job's error.

    A `manifoundation.core.errors.ScienceError` carries its contract type (``code``), and its ``field`` when it names
    one (the planner's errors: ``waypoints[2]`` → ``detail`` field ``waypoints.2``); pydantic's `ValidationError` (a
    queue payload is input too) is a ``ValidationError`` naming each field; anything else is a fault of the service, an
    ``InternalError`` that names the exception's class, never a 4xx that blames the caller.
    """
    import pydantic

    from manifoundation.core.errors import ScienceError

    if isinstance(exc, pydantic.ValidationError):
        detail = field_errors(exc)
        return ErrorBody.of(ErrorType.VALIDATION_ERROR, summary(detail)[:2000], detail)
    message = str(exc) or exc.__class__.__name__
    if isinstance(exc, ScienceError):
        kind = ErrorType.parse(exc.code) or ErrorType.INTERNAL_ERROR
        field = getattr(exc, "field", None)
        if not isinstance(field, str) or not field:
            return ErrorBody.of(kind, message[:2000])
        path = field.replace("[", ".").replace("]", "")
        problem = message.partition(": ")[2] or message  # the message starts with a field name
        return ErrorBody.of(kind, message[:2000], [FieldError(field=path, problem=problem[:2000])])
    return ErrorBody.of(ErrorType.INTERNAL_ERROR, f"{exc.__class__.__name__}: {message}"[:2000])
