"""`GrpcJob` and `AsyncGrpcJob`: a queued job followed over gRPC (``GrpcClient.job``, ``AsyncGrpcClient.job``).

A job is followed on its ``WatchJob`` stream; when the stream ends before the job did, or its last message came
without the answer, the job is read once more (`settled` decides), so `wait` always sees the job in full.
"""

from __future__ import annotations

from collections.abc import AsyncIterator, Callable, Iterator
from operator import attrgetter
from typing import Protocol

from manifoundation.contract import JobPublic, JobState, SynthesisResult
from manifoundation.contract.plans import PlanResult
from manifoundation.sdk.tracking import job_result, plan_result

Answer = Callable[[JobPublic], object]
"""What a succeeded job must carry to be complete (its result, its plan)."""
RESULT: Answer = attrgetter("result")
PLAN: Answer = attrgetter("plan")


class JobCalls(Protocol):
    """What a job needs of its client (`GrpcClient` has these)."""

    def get(self, job_id: str, *, with_result: bool = True) -> JobPublic: ...

    def cancel(self, job_id: str) -> JobPublic: ...

    def watch(
        self, job_id: str, *, timeout: float | None = None, cancel_on_disconnect: bool = False
    ) -> Iterator[JobPublic]: ...


class AsyncJobCalls(Protocol):
    """What an awaited job needs of its client (`AsyncGrpcClient` has these)."""

    async def get(self, job_id: str, *, with_result: bool = True) -> JobPublic: ...

    async def cancel(self, job_id: str) -> JobPublic: ...

    def watch(
        self, job_id: str, *, timeout: float | None = None, cancel_on_disconnect: bool = False
    ) -> AsyncIterator[JobPublic]: ...


def settled(last: JobPublic | None, answer: Answer | None) -> JobPublic | None:
    """The last job a stream gave when it is final and complete; None: read the job once more (the stream
    ended early, or its final job came without ``answer``)."""
    if last is None or not last.state.terminal:
        return None
    if last.state is JobState.SUCCEEDED and answer is not None and answer(last) is None:
        return None
    return last


class GrpcJob:
    """A queued synthesis over gRPC: the calls of `manifoundation.sdk.Job` (status, cancel, wait, events)."""

    def __init__(self, client: JobCalls, job_id: str) -> None:
        self.client = client
        self.id = job_id

    def __repr__(self) -> str:
        return f"GrpcJob({self.id!r})"

    def status(self) -> JobPublic:
        """The job now (with its result or error when finished)."""
        return self.client.get(self.id)

    def cancel(self) -> JobPublic:
        """Ask the service to cancel the job."""
        return self.client.cancel(self.id)

    def events(self, timeout: float | None = None) -> Iterator[JobPublic]:
        """The job's progress as it happens (`GrpcClient.watch`), ending with its final state."""
        return self.client.watch(self.id, timeout=timeout)

    def wait(self, timeout: float | None = None) -> SynthesisResult:
        """Wait until the job finishes (following its stream) and return its result.

        Raises:
            TimeoutError: still running after ``timeout`` seconds (None: wait for ever).
            JobFailed: it failed, was cancelled or expired.
        """
        return job_result(self.finished(timeout, answer=RESULT))

    def plan_result(self, timeout: float | None = None) -> PlanResult:
        """Wait until a plan job finishes and return its plan (raises as `wait`)."""
        return plan_result(self.finished(timeout, answer=PLAN))

    def finished(self, timeout: float | None = None, answer: Answer | None = None) -> JobPublic:
        """The job once it has ended, following its stream (``answer``: what a succeeded job must carry, else
        it is read once more)."""
        last: JobPublic | None = None
        for job in self.events(timeout):
            last = job
        done = settled(last, answer)
        return self.status() if done is None else done


class AsyncGrpcJob:
    """A queued synthesis over gRPC, awaited: the calls of `GrpcJob` (``events`` an async iterator)."""

    def __init__(self, client: AsyncJobCalls, job_id: str) -> None:
        self.client = client
        self.id = job_id

    def __repr__(self) -> str:
        return f"AsyncGrpcJob({self.id!r})"

    async def status(self) -> JobPublic:
        """The job now (with its result or error when finished)."""
        return await self.client.get(self.id)

    async def cancel(self) -> JobPublic:
        """Ask the service to cancel the job."""
        return await self.client.cancel(self.id)

    def events(self, timeout: float | None = None) -> AsyncIterator[JobPublic]:
        """The job's progress as it happens (`AsyncGrpcClient.watch`), ending with its final state."""
        return self.client.watch(self.id, timeout=timeout)

    async def wait(self, timeout: float | None = None) -> SynthesisResult:
        """Wait until the job finishes and return its result (raises as `GrpcJob.wait`)."""
        return job_result(await self.finished(timeout, answer=RESULT))

    async def plan_result(self, timeout: float | None = None) -> PlanResult:
        """Wait until a plan job finishes and return its plan (raises as `GrpcJob.wait`)."""
        return plan_result(await self.finished(timeout, answer=PLAN))

    async def finished(self, timeout: float | None = None, answer: Answer | None = None) -> JobPublic:
        """The job once it has ended, following its stream (as `GrpcJob.finished`)."""
        last: JobPublic | None = None
        async for job in self.events(timeout):
            last = job
        done = settled(last, answer)
        return await self.status() if done is None else done
