"""The clients' one base (`SyncAPI`) over an injected `Transport`: its logic without a network (a transport in
memory), the way a polling transport (HTTP) and a streaming one (gRPC) are each followed."""

from __future__ import annotations

from collections.abc import Iterator

import pytest

from manifoundation.contract import (
    BatchItem,
    BatchPublic,
    JobCreated,
    JobPublic,
    JobState,
    PlanRequest,
    RobotPublic,
    RobotRegister,
    SynthesisRequest,
    SynthesisResult,
)
from manifoundation.sdk import JobFailed, NeedsHttp, NotFound, TimeoutError
from manifoundation.sdk._api import SyncAPI, Transport
from manifoundation.sdk.compat import VersionCheck
from tests.api.helpers import request_body

RESULT = SynthesisResult(model_version="memory", proposals=[], hand="leap")


def job(state: JobState, result: SynthesisResult | None = None) -> JobPublic:
    return JobPublic(id="j1", state=state, created_at=0.0, result=result)


class Memory(Transport):
    """A transport that answers from memory: ``states`` are what ``GetJob`` shows, one per call; ``stream`` what
    ``WatchJob`` gives; ``items`` what ``WatchBatch`` gives (a `TimeoutError` after them when ``stalls``)."""

    def __init__(self, states: list[JobPublic], *, streams: bool = False, stream: list[JobPublic] | None = None):
        self.states, self.stream, self.items, self.stalls = states, stream or [], list[BatchItem](), False
        self.streams = streams  # type: ignore[misc]  # a class constant of the real transports
        self.versions = VersionCheck("memory")
        self.slept: list[float] = []
        self.closed = False

    def sleep(self, seconds: float) -> None:
        self.slept.append(seconds)

    def close(self) -> None:
        self.closed = True

    def synthesize(self, request: SynthesisRequest) -> SynthesisResult | JobCreated:
        return JobCreated(id="j1", state=JobState.QUEUED, url="/v1/jobs/j1")  # the service answered before the end

    def submit(self, request: SynthesisRequest) -> str:
        return "j1"

    def submit_plan(self, request: PlanRequest) -> str:
        return "j1"

    def job(self, job_id: str, with_result: bool = True) -> JobPublic:
        return self.states.pop(0) if len(self.states) > 1 else self.states[0]

    def cancel(self, job_id: str) -> JobPublic:
        return job(JobState.CANCELLED)

    def events(self, job_id: str, timeout: float | None) -> Iterator[JobPublic]:
        yield from self.stream

    def submit_batch(self, requests: list[SynthesisRequest]) -> str:
        return "b1"

    def batch(self, batch_id: str, offset: int, limit: int) -> BatchPublic:
        return BatchPublic(id=batch_id, total=2, counts={}, done=False, items=[], offset=offset, limit=limit)

    def batch_items(self, batch_id: str, timeout: float | None) -> Iterator[BatchItem]:
        yield from self.items
        if self.stalls:
            raise TimeoutError("stream deadline")

    def robots(self) -> list[RobotPublic]:
        return [RobotPublic(name="leap", builtin=True, dof=16, joint_names=[], lower=[], upper=[], fingertips=[])]

    def register_robot(self, body: RobotRegister) -> RobotPublic:
        raise AssertionError("not called")


def request() -> SynthesisRequest:
    return SynthesisRequest.model_validate(request_body("leap", 64))


def test_a_polling_transport_is_polled_until_the_job_ends() -> None:
    memory = Memory([job(JobState.QUEUED), job(JobState.RUNNING), job(JobState.SUCCEEDED, RESULT)])
    with SyncAPI(memory) as client:
        assert client.synthesize(request()) == RESULT  # JobCreated: the base waits on the job
        assert len(memory.slept) == 2 and client.versions is memory.versions
    assert memory.closed


def test_a_streaming_transport_is_followed_then_read_once_more_when_the_stream_lacks_the_answer() -> None:
    memory = Memory([job(JobState.SUCCEEDED, RESULT)], streams=True, stream=[job(JobState.SUCCEEDED)])
    assert SyncAPI(memory).submit(request()).wait() == RESULT and memory.slept == []
    failed = Memory([job(JobState.FAILED)], streams=True, stream=[job(JobState.RUNNING), job(JobState.FAILED)])
    with pytest.raises(JobFailed):
        SyncAPI(failed).job("j1").wait()


def test_a_streamed_batch_times_out_with_its_count() -> None:
    memory = Memory([job(JobState.QUEUED)], streams=True)
    memory.items, memory.stalls = [BatchItem(index=1, job_id="j2", state=JobState.SUCCEEDED, result=RESULT)], True
    batch = SyncAPI(memory).submit_batch([request(), request()])
    with pytest.raises(TimeoutError, match="batch b1: 1/2 done after 5 s"):
        batch.wait(timeout=5)


def test_defaults_of_a_transport_without_the_http_only_calls() -> None:
    client = SyncAPI(Memory([job(JobState.QUEUED)]))
    assert client.robot("leap").name == "leap"  # found in robots()
    with pytest.raises(NotFound):
        client.robot("allegro")
    for call in (lambda: client.jobs(), lambda: client.delete_robot("x"), lambda: client.health()):
        with pytest.raises(NeedsHttp):
            call()
