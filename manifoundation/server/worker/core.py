"""The worker core, the same for every transport: decode → job input → run → encoded outcome + timings.

Both worker programs are thin shells around it: the embedded backend's child process
(`manifoundation.server.worker.child`, fed over a pipe by `mani serve`) and the Redis worker
(`manifoundation.server.worker.worker`, fed by a stream). A shell hands the core `RawJob`s (the request still as the
msgpack bytes the API encoded once) and gets `Finished` outcomes back (a result already encoded once, as the bytes the
queue stores), so neither shell decodes, validates or encodes a request or a result itself. The one validation at the
queue → worker boundary is `decode`'s; the result is built once by the pipeline and encoded once here. A job's ``kind``
says what its bytes are: a `SynthesisRequest` (run in micro-batches) or a `PlanRequest` (run alone, after the batch's
syntheses, through `Pipeline.plan`).

Timings, one meaning on both backends (seconds): ``queue`` from submission to the start in a worker, ``run`` from
that start to the outcome, ``total`` their sum; plus the pipeline's own per-stage figures (``network``,
``refinement``, ``verification``...).
"""

from __future__ import annotations

import logging
import os
import socket
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from manifoundation.contract import (
    ErrorBody,
    ErrorType,
    JobKind,
    JobProgress,
    JobState,
    PlanRequest,
    PlanResult,
    RobotPublic,
    RobotRegister,
    Stage,
    SynthesisRequest,
    SynthesisResult,
    WorkerPublic,
)
from manifoundation.contract.codec import pack, unpack
from manifoundation.server.queue.records import STILL_LOADING, state_for_error
from manifoundation.server.worker.heap import HeapTrimmer
from manifoundation.server.worker.logs import job_context
from manifoundation.server.worker.overrun import DeadlinePassed, stopped_at
from manifoundation.server.worker.pipeline import CancelFn, JobInput, Pipeline, PlanJob, error_from_exception
from manifoundation.server.worker.runner import run_batch, run_plan

log = logging.getLogger("manifoundation.server.worker.core")

PROGRESS_INTERVAL_S = 0.05
"""At most one progress update per job in this many seconds (a job shorter than that reports none)."""

ProgressSink = Callable[[str, JobProgress], None]
"""sink(job_id, progress): where a shell sends a job's (already throttled) progress."""


@dataclass
class RawJob:
    """A job as a transport delivers it: the request as the queue's bytes, not yet decoded."""

    id: str
    request: bytes
    deadline: float | None = None
    robot: bytes | None = None  # the registered robot (msgpack of `RobotRegister`) when the request names one
    request_id: str | None = None
    queued_for: float = 0.0  # seconds between submission and this delivery's start
    kind: JobKind = JobKind.SYNTHESIS  # what ``request`` holds


@dataclass
class Finished:
    """A job's outcome as a transport stores it."""

    id: str
    state: JobState
    result: bytes | None = None  # msgpack of the `SynthesisResult` (a plan: `PlanResult`), encoded once
    error: ErrorBody | None = None
    timings: dict[str, float] = field(default_factory=dict)


@dataclass
class _Started:
    job: JobInput | PlanJob
    started: float
    queued_for: float


class WorkerCore:
    """The pipeline, loaded once per process, behind the decode / run / encode steps (see module doc)."""

    def __init__(self, pipeline: Pipeline) -> None:
        self.pipeline = pipeline
        self.heap = HeapTrimmer()

    def info(self, worker_id: str) -> WorkerPublic:
        """What this worker publishes about itself."""
        now = time.time()
        return WorkerPublic(
            id=worker_id, host=socket.gethostname(), pid=os.getpid(), started_at=now, last_heartbeat=now,
            model_loaded=self.pipeline.model_loaded, model_version=self.pipeline.model_version,
        )  # fmt: skip

    def robots(self) -> list[RobotPublic]:
        """The built-in hands this worker can use."""
        return self.pipeline.robots()

    def validate_robot(
        self, raw: bytes, deadline: float | None = None, answer: Callable[[dict[str, Any]], None] | None = None
    ) -> dict[str, Any]:
        """A user's robot registration, loaded with the hardened loader, as the answer a shell sends back (never
        raises): ``{"robot": RobotPublic}`` (its ``stored_bytes`` the registration's own, what the key's byte quota
        counts, whatever the pipeline), or ``{"error": why}`` (``"type": "DeadlineExceeded"`` for a deadline).

        ``deadline`` (epoch s): a registration still loading then is answered through ``answer`` and this process
        ends (`manifoundation.server.worker.overrun`; its supervisor replaces it); one past it is not loaded.
        """
        try:
            robot = RobotRegister.model_validate(unpack(raw))
            with stopped_at(deadline, lambda: (answer or _nobody)(_overrun(STILL_LOADING))):
                public = self.pipeline.validate_robot(robot)
        except DeadlinePassed as exc:
            log.warning("registration dropped before start: %s", exc)
            return _overrun(f"no worker was free to load the robot before it ({exc})")
        except Exception as exc:
            return {"error": str(exc) or exc.__class__.__name__}
        public = public.model_copy(update={"stored_bytes": robot.stored_bytes})
        return {"robot": public.model_dump(mode="python", exclude_none=True)}

    def run(self, raw_jobs: list[RawJob], sink: ProgressSink, should_cancel: CancelFn) -> list[Finished]:
        """Decode, run and encode one micro-batch; one outcome per job, in order; never raises.

        A payload that does not decode or validate fails its own job only (a queue payload is input too).
        """
        finished: dict[str, Finished] = {}
        started: list[_Started] = []
        for raw in raw_jobs:
            t0 = time.perf_counter()
            with job_context(raw.id, raw.request_id):
                try:
                    job = self._decode(raw)
                except Exception as exc:
                    error = error_from_exception(exc)
                    log.warning("job rejected", extra={"error": error.error})
                    finished[raw.id] = Finished(raw.id, state_for_error(error), error=error)
                    continue
                log.info("job started")
            started.append(_Started(job, t0, raw.queued_for))
        syntheses = [s.job for s in started if isinstance(s.job, JobInput)]
        outcomes: dict[str, SynthesisResult | PlanResult | ErrorBody] = {}
        outcomes.update(run_batch(self.pipeline, syntheses, throttled(sink), should_cancel))
        for s in started:
            if isinstance(s.job, PlanJob):
                s.started = time.perf_counter()  # it waited for the batch's syntheses: that is not its run time
                outcomes[s.job.id] = run_plan(self.pipeline, s.job, counted(sink), should_cancel)
            outcome = outcomes[s.job.id]
            run_s = time.perf_counter() - s.started
            timings = dict(outcome.timings) if isinstance(outcome, SynthesisResult | PlanResult) else {}
            timings.update(queue=s.queued_for, run=run_s, total=s.queued_for + run_s)
            with job_context(s.job.id, s.job.request_id):
                finished[s.job.id] = _encoded(s.job.id, outcome, timings)
                log.info("job finished", extra={"state": finished[s.job.id].state.value})
        self.heap.maybe_trim()
        return [finished[raw.id] for raw in raw_jobs]

    @staticmethod
    def _decode(raw: RawJob) -> JobInput | PlanJob:
        """The one validation of a request on the worker side."""
        robot = RobotRegister.model_validate(unpack(raw.robot)) if raw.robot else None
        if raw.kind is JobKind.PLAN:
            plan = PlanRequest.model_validate(unpack(raw.request))
            return PlanJob(id=raw.id, request=plan, deadline=raw.deadline, robot=robot, request_id=raw.request_id)
        request = SynthesisRequest.model_validate(unpack(raw.request))
        return JobInput(id=raw.id, request=request, deadline=raw.deadline, robot=robot, request_id=raw.request_id)


def runs_of(raw_jobs: list[RawJob]) -> list[list[RawJob]]:
    """The micro-batches a transport's delivery is run as: its syntheses together, then each plan alone (a plan
    takes seconds to minutes; the syntheses' outcomes are not held back for it)."""
    syntheses = [raw for raw in raw_jobs if raw.kind is not JobKind.PLAN]
    return ([syntheses] if syntheses else []) + [[raw] for raw in raw_jobs if raw.kind is JobKind.PLAN]


def _overrun(what: str) -> dict[str, Any]:
    return {"error": what, "type": ErrorType.DEADLINE_EXCEEDED.value}


def _nobody(_: dict[str, Any]) -> None:
    """No one to answer (the service side says it)."""


def _encoded(job_id: str, outcome: SynthesisResult | PlanResult | ErrorBody, timings: dict[str, float]) -> Finished:
    if isinstance(outcome, ErrorBody):
        return Finished(job_id, state_for_error(outcome), error=outcome, timings=timings)
    result = pack(outcome.model_dump(mode="python", exclude_none=True))
    return Finished(job_id, JobState.SUCCEEDED, result=result, timings=timings)


def throttled(sink: ProgressSink, interval: float = PROGRESS_INTERVAL_S) -> Callable[..., None]:
    """The pipeline's ``progress(job_id, stage, fraction, iteration, max_iterations)`` → ``sink``, at most one
    update per job every ``interval`` seconds (counted from the batch's start)."""
    start = time.monotonic()
    last: dict[str, float] = {}

    def progress(job_id: str, stage: Stage, fraction: float, iteration: int | None, maximum: int | None) -> None:
        now = time.monotonic()
        if now - last.get(job_id, start) < interval:
            return
        last[job_id] = now
        p = JobProgress(stage=stage, fraction=min(max(fraction, 0.0), 1.0), iteration=iteration, max_iterations=maximum)
        sink(job_id, p)

    return progress


def counted(sink: ProgressSink, interval: float = PROGRESS_INTERVAL_S) -> Callable[[str, Stage, int, int], None]:
    """A plan's ``progress(job_id, stage, completed, total)`` → ``sink``, throttled as `throttled`, except that
    the first and the last report of a stage always pass (a stage change is never hidden)."""
    last: dict[str, tuple[float, Stage]] = {}

    def progress(job_id: str, stage: Stage, completed: int, total: int) -> None:
        now = time.monotonic()
        stamp, previous = last.get(job_id, (float("-inf"), None))
        if stage is previous and completed < total and now - stamp < interval:
            return
        last[job_id] = (now, stage)
        fraction = 1.0 if total <= 0 else min(max(completed / total, 0.0), 1.0)
        sink(job_id, JobProgress(stage=stage, fraction=fraction, completed=completed, total=total))

    return progress
