"""`GrpcJob`: a queued job followed over gRPC (`clients.sdk.grpc_client.GrpcClient.job`)."""

from __future__ import annotations

from collections.abc import Callable, Iterator
from typing import Protocol

from clients.schemas import JobPublic, JobState, SynthesisResult
from clients.schemas.plans import PlanResult
from clients.sdk.tracking import job_result, plan_result


class JobCalls(Protocol):
    """What a job needs of its client (`GrpcClient` has these)."""

    def get(self, job_id: str, *, with_result: bool = True) -> JobPublic: ...

    def cancel(self, job_id: str) -> JobPublic: ...

    def watch(
        self, job_id: str, *, timeout: float | None = None, cancel_on_disconnect: bool = False
    ) -> Iterator[JobPublic]: ...


class GrpcJob:
    """A queued synthesis over gRPC: the calls of `clients.sdk.Job` (status, cancel, wait, events)."""

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
        return job_result(self.finished(timeout, answer=lambda job: job.result))

    def plan_result(self, timeout: float | None = None) -> PlanResult:
        """Wait until a plan job finishes and return its plan (raises as `wait`)."""
        return plan_result(self.finished(timeout, answer=lambda job: job.plan))

    def finished(self, timeout: float | None = None, answer: Callable[[JobPublic], object] | None = None) -> JobPublic:
        """The job once it has ended, following its stream (``answer``: what a succeeded job must carry, else
        it is read once more)."""
        last: JobPublic | None = None
        for job in self.events(timeout):
            last = job
        missing = last is not None and last.state is JobState.SUCCEEDED and answer is not None and answer(last) is None
        if last is None or not last.state.terminal or missing:
            last = self.status()  # the stream ended early, or its final job came without the answer
        return last
