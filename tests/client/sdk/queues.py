"""`ScriptedQueue`: the service tests' in-memory `FakeQueue`, with jobs that run for a while and may fail.

The SDK waits on jobs (polls, Server-Sent Events, batch pages), so its tests need jobs that stay *running* for a
known number of looks before they end. Time would make that flaky and slow; here a job advances each time the API
reads it through the queue (`get`: a ``GET /v1/jobs/{id}``, a batch page, one poll of an event stream, a cancel).
The synchronous route's wait does not advance it: a held job outlives a ``POST /v1/synthesize`` wait, and the
answer is a 202.
"""

from __future__ import annotations

import asyncio
import time
from dataclasses import dataclass

from manifoundation.contract import ErrorBody, ErrorType, JobProgress, JobPublic, JobState, Stage, SynthesisRequest
from tests.api.fakes import HAND as FAKE_HAND
from tests.api.fakes import FakeQueue

HAND = FAKE_HAND.name
"""The one built-in hand of the queue (``fake_hand``): the requests that reach the app name it."""

FAILURE = ErrorBody.of(ErrorType.INTERNAL_ERROR, "refinement diverged")
"""A job error for ``ScriptedQueue.error`` (a worker's fault: the app answers it with 500)."""

FOREVER = 10**9
"""``running_reads`` for jobs that never end within a test."""


@dataclass
class _Plan:
    """How one job ends: after ``reads_left`` more reads answered running, with ``error`` (None: succeeded)."""

    reads_left: int | None
    error: ErrorBody | None


class ScriptedQueue(FakeQueue):
    """A `FakeQueue` whose jobs end after a number of reads, succeeded or failed.

    Both knobs apply to the jobs submitted after they are set (each job keeps the plan it was submitted with).

    Attributes:
        running_reads: reads of a job answered *running* before the next read ends it; None: jobs end as they are
            submitted (`FakeQueue`'s way; a synchronous request then answers 200 or the job's error).
        error: what jobs end with; None: a result (`tests.api.fakes.fake_result`).
    """

    def __init__(self) -> None:
        super().__init__()
        self.running_reads: int | None = None
        self.error: ErrorBody | None = None
        self._plans: dict[str, _Plan] = {}

    def job_ids(self) -> list[str]:
        """Every job's id, oldest first."""
        return list(self.jobs)

    async def submit(
        self, requests: list[SynthesisRequest], *, batch_id: str | None = None, deadline: float | None = None,
        request_id: str | None = None, owner: str | None = None,
    ) -> list[str]:  # fmt: skip
        self.hold = self.running_reads is not None
        ids = await super().submit(requests, batch_id=batch_id, deadline=deadline, request_id=request_id, owner=owner)
        for job_id in ids:
            self._plans[job_id] = _Plan(self.running_reads, self.error)
        return ids

    def finish(self, job_id: str, error: ErrorBody | None = None) -> None:
        """End the job: with ``error``, else with its plan's error (set in `submit`), else a result."""
        plan = self._plans.get(job_id)
        if error is None and plan is None:
            error = self.error  # `FakeQueue.submit` finishes a job before `submit` above records its plan
        super().finish(job_id, error or (plan.error if plan else None))

    async def get(self, job_id: str, *, with_result: bool = True, owner: str | None = None) -> JobPublic:
        await super().get(job_id, with_result=False, owner=owner)  # unknown, or another owner's: JobNotFound
        self._advance(job_id)
        return await super().get(job_id, with_result=with_result, owner=owner)

    async def wait(self, job_id: str, timeout: float) -> JobPublic:
        """As `FakeQueue.wait`, without advancing the job (only reads do)."""
        end = time.monotonic() + timeout
        while not (job := await super().get(job_id)).state.terminal and time.monotonic() < end:
            await asyncio.sleep(0.005)
        return job

    def _advance(self, job_id: str) -> None:
        """One read of a held job: *running* while its plan has reads left, then it ends."""
        job, plan = self.jobs[job_id], self._plans.get(job_id)
        if job.state.terminal or plan is None or plan.reads_left is None:
            return
        if plan.reads_left > 0:
            plan.reads_left -= 1
            job.state = JobState.RUNNING
            job.started_at = job.started_at or time.time()
            job.progress = JobProgress(stage=Stage.REFINEMENT, fraction=0.5)
            return
        self.finish(job_id)
