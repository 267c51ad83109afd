"""Run one micro-batch through a pipeline, backend-agnostic: drop expired and cancelled jobs first, isolate
failures (a crashing batch is retried job by job so only the bad job fails), never raise. Whatever is logged while
a single job runs (a batch of one, or the one-by-one retries) carries its job id and request id."""

from __future__ import annotations

import contextlib
import logging
import time

from manifoundation.contract import ErrorBody, PlanResult, SynthesisResult
from manifoundation.server.queue.records import cancelled_error, deadline_error
from manifoundation.server.worker.logs import job_context
from manifoundation.server.worker.pipeline import (
    CancelFn,
    JobInput,
    Outcome,
    Pipeline,
    PlanJob,
    PlanOutcome,
    PlanProgressFn,
    ProgressFn,
    error_from_exception,
)

log = logging.getLogger("manifoundation.server.worker.runner")


def run_batch(
    pipeline: Pipeline, jobs: list[JobInput], progress: ProgressFn, should_cancel: CancelFn
) -> dict[str, Outcome]:
    """Outcome of every job of ``jobs`` by id."""
    outcomes: dict[str, Outcome] = {}
    live: list[JobInput] = []
    now = time.time()
    for job in jobs:
        if should_cancel(job.id):
            outcomes[job.id] = cancelled_error()
        elif job.deadline is not None and job.deadline <= now:
            outcomes[job.id] = deadline_error()
        else:
            live.append(job)
    by_id = {job.id: job for job in jobs}
    for job_id, outcome in outcomes.items():
        with job_context(job_id, by_id[job_id].request_id):
            reason = outcome.type if isinstance(outcome, ErrorBody) else ""
            log.info("job dropped before start", extra={"reason": reason})
    if not live:
        return outcomes
    try:
        with _context(live):
            results = _call(pipeline, live, progress, should_cancel)
    except Exception as exc:  # a crashed pipeline call fails jobs, never the worker
        if len(live) == 1:
            outcomes[live[0].id] = _failed(live[0], exc)
            return outcomes
        log.warning("batch of %d failed (%s); retrying one by one", len(live), exc)
        for job in live:
            try:
                with _context([job]):
                    outcomes[job.id] = _call(pipeline, [job], progress, should_cancel)[0]
            except Exception as one:
                outcomes[job.id] = _failed(job, one)
        return outcomes
    outcomes.update({job.id: result for job, result in zip(live, results, strict=True)})
    return outcomes


def run_plan(pipeline: Pipeline, job: PlanJob, progress: PlanProgressFn, should_cancel: CancelFn) -> PlanOutcome:
    """The outcome of one plan job: dropped when cancelled or expired before it starts, a failure when the
    pipeline raises (never raises itself)."""
    with job_context(job.id, job.request_id):
        if should_cancel(job.id):
            log.info("job dropped before start", extra={"reason": "Cancelled"})
            return cancelled_error()
        if job.deadline is not None and job.deadline <= time.time():
            log.info("job dropped before start", extra={"reason": "DeadlineExceeded"})
            return deadline_error()
        try:
            outcome = pipeline.plan(job, progress, should_cancel)
        except Exception as exc:  # a crashed plan fails its job, never the worker
            log.exception("pipeline failed")
            return error_from_exception(exc)
    if not isinstance(outcome, PlanResult | ErrorBody):
        return error_from_exception(RuntimeError(f"pipeline answered a {type(outcome).__name__} for a plan"))
    return outcome


def _context(jobs: list[JobInput]) -> contextlib.AbstractContextManager[None]:
    """The job's log context when ``jobs`` is one job; a batch of several is nobody's in particular."""
    return job_context(jobs[0].id, jobs[0].request_id) if len(jobs) == 1 else contextlib.nullcontext()


def _call(pipeline: Pipeline, jobs: list[JobInput], progress: ProgressFn, should_cancel: CancelFn) -> list[Outcome]:
    results = pipeline.run(jobs, progress, should_cancel)
    if len(results) != len(jobs) or not all(isinstance(r, SynthesisResult | ErrorBody) for r in results):
        raise RuntimeError(f"pipeline returned {len(results)} outcomes for {len(jobs)} jobs")
    return results


def _failed(job: JobInput, exc: Exception) -> ErrorBody:
    with job_context(job.id, job.request_id):
        log.exception("pipeline failed")
    return error_from_exception(exc)
