"""The `manifoundation.v1.ManiFoundation` service: each RPC over the same queue and objects as the HTTP routes.

`Synthesize` names its job in the initial and the trailing metadata (``x-job-id``), failed or not.

Deadlines and cancellation: `Synthesize` gives its job the deadline min(now + ``options.timeout``, the call's
deadline), so the worker stops (the job ends *expired*) when the client would stop waiting; a client that cancels
or disconnects before its deadline cancels the job (it ends *cancelled*; the worker stops at its next stage or
iteration). `WatchJob` does the same when asked (``cancel_on_disconnect``); a job from `SubmitJob` outlives its
watchers by default.
"""

from __future__ import annotations

import asyncio
import logging
import time
from collections.abc import AsyncIterator
from typing import TYPE_CHECKING, Any

import grpc

from manifoundation.contract import (
    DEFAULT_TIMEOUT_S,
    MAX_BATCH_SIZE,
    BatchItem,
    ErrorBody,
    FieldError,
    JobPublic,
    JobState,
    PlanRequest,
    RobotRegister,
    SynthesisRequest,
)
from manifoundation.contract.protos.convert import to_proto
from manifoundation.contract.protos.v1 import manifoundation_pb2 as pb
from manifoundation.contract.protos.v1 import manifoundation_pb2_grpc as pb_grpc
from manifoundation.server.api.batch_pages import batch_page
from manifoundation.server.api.errors import InvalidInput, PayloadTooLarge
from manifoundation.server.api.grpc.calls import GrpcMetrics, send_initial_metadata, streaming, unary
from manifoundation.server.api.grpc.errors import JobFailed
from manifoundation.server.api.grpc.submit import LargeMessage, Submission
from manifoundation.server.api.security import Caller
from manifoundation.server.api.waiting import wait_for_job

if TYPE_CHECKING:
    from manifoundation.server.api.services import AppServices

log = logging.getLogger("manifoundation.server.api.grpc")
EXPIRY_NOTICE_S = 10.0  # a job past its deadline is expired by the queue within this
DEADLINE_SLACK_S = 0.05  # a call that ends this close to its job's deadline let the deadline expire the job
_WITHOUT_ERROR = {
    JobState.CANCELLED: "Cancelled",
    JobState.EXPIRED: "DeadlineExceeded",
    JobState.FAILED: "InternalError",
}


def _call_deadline(context: grpc.aio.ServicerContext) -> float | None:
    """The call's deadline as Unix time (None: the client set none)."""
    remaining = context.time_remaining()
    return None if remaining is None else time.time() + remaining


class ManiFoundationService(pb_grpc.ManiFoundationServicer):
    """The RPCs; ``services``: the app's shared objects (queue, robots, settings, limiters, metrics)."""

    def __init__(self, services: AppServices) -> None:
        self.services = services
        self.submission = Submission(services)
        self.metrics = GrpcMetrics(services.metrics)

    @unary
    async def Synthesize(self, request: pb.SynthesisRequest, context: Any, caller: Caller) -> pb.SynthesisResult:
        """Submit, wait for the end, answer the result (or the job's error as the call's status)."""
        message: pb.SynthesisRequest | SynthesisRequest = request
        if isinstance(request, LargeMessage):  # its timeout is read from the request decoded off the loop
            message = await self.submission.validate(request, SynthesisRequest)
            timeout = message.options.timeout
        else:
            timeout = request.options.timeout if request.options.HasField("timeout") else DEFAULT_TIMEOUT_S
        call_deadline = _call_deadline(context)
        deadline = min(time.time() + max(0.0, timeout), call_deadline or float("inf"))
        _, job_id = await self.submission.one(message, caller, context, kind="sync", deadline=deadline)
        await send_initial_metadata(self.services, context, ("x-job-id", job_id))
        try:
            job = await self._wait(job_id, deadline)
        except asyncio.CancelledError:
            if call_deadline is None or time.time() < call_deadline - DEADLINE_SLACK_S:
                await self.submission.queue.cancel(job_id)  # the client cancelled or went away: stop the work
            raise
        self.services.metrics.observe_job(job)
        if job.result is None:
            kind = _WITHOUT_ERROR.get(job.state, "DeadlineExceeded")
            raise JobFailed(job.error or ErrorBody(error=f"job ended {job.state.value}", type=kind), job_id)
        context.set_trailing_metadata((("x-job-id", job_id),))
        return to_proto(job.result, pb.SynthesisResult)

    async def _wait(self, job_id: str, deadline: float) -> JobPublic:
        """The job once terminal; its deadline bounds the wait (plus the queue's time to notice it)."""
        seconds = deadline + EXPIRY_NOTICE_S - time.time()
        return await wait_for_job(self.services, self.submission.queue, job_id, seconds, fetch_with="with GetJob")

    @unary
    async def SubmitJob(self, request: pb.SynthesisRequest, context: Any, caller: Caller) -> pb.JobCreated:
        _, job_id = await self.submission.one(request, caller, context, kind="async")
        return pb.JobCreated(id=job_id, state=JobState.QUEUED.value)

    @unary
    async def GetJob(self, request: pb.GetJobRequest, context: Any, caller: Caller) -> pb.JobPublic:
        job = await self.submission.queue.get(request.id, with_result=not request.without_result, owner=caller.scope)
        self.services.metrics.observe_job(job)
        return to_proto(job, pb.JobPublic)

    @unary
    async def CancelJob(self, request: pb.JobRef, context: Any, caller: Caller) -> pb.JobPublic:
        return to_proto(await self.submission.queue.cancel(request.id, owner=caller.scope), pb.JobPublic)

    @streaming
    async def WatchJob(self, request: pb.WatchJobRequest, context: Any, caller: Caller) -> AsyncIterator[pb.JobPublic]:
        queue = self.submission.queue
        await queue.get(request.id, with_result=False, owner=caller.scope)  # NOT_FOUND before the stream
        ended = False
        try:
            async for job in queue.events(request.id, interval=self.services.settings.sse_interval):
                if job.state.terminal:
                    break
                yield to_proto(job, pb.JobPublic)
            ended = True
            yield to_proto(await queue.get(request.id), pb.JobPublic)
        except asyncio.CancelledError:
            if request.cancel_on_disconnect and not ended:
                await queue.cancel(request.id)
            raise

    @unary
    async def SubmitBatch(self, request: pb.BatchCreate, context: Any, caller: Caller) -> pb.BatchPublic:
        batch_id = await self.submission.batch(request, caller, context)
        batch = await self.submission.submitter(caller, context).first_page(batch_id)
        return to_proto(batch, pb.BatchPublic)

    @unary
    async def SubmitBatchStream(
        self, request: AsyncIterator[pb.MessagePiece], context: Any, caller: Caller
    ) -> pb.BatchPublic:
        batch_id = await self.submission.batch_streamed(request, caller, context)
        batch = await self.submission.submitter(caller, context).first_page(batch_id)
        return to_proto(batch, pb.BatchPublic)

    @unary
    async def GetBatch(self, request: pb.GetBatchRequest, context: Any, caller: Caller) -> pb.BatchPublic:
        queue, settings = self.submission.queue, self.services.settings
        offset, limit = request.offset, request.limit if request.HasField("limit") else 100
        if offset < 0 or not 1 <= limit <= MAX_BATCH_SIZE:
            field = "offset" if offset < 0 else "limit"
            problem = "must be ≥ 0" if offset < 0 else f"must be 1..{MAX_BATCH_SIZE}"
            raise InvalidInput(f"{field}: {problem}", detail=[FieldError(field=field, problem=problem)])
        batch = await batch_page(queue, request.id, caller.scope, offset, min(limit, settings.batch_page_max))
        return to_proto(batch, pb.BatchPublic)

    @streaming
    async def WatchBatch(self, request: pb.BatchRef, context: Any, caller: Caller) -> AsyncIterator[pb.BatchItem]:
        queue = self.submission.queue
        job_ids = await queue.batch_job_ids(request.id, owner=caller.scope)
        waiting = dict(enumerate(job_ids))
        while waiting:
            states = await asyncio.gather(*(queue.get(j, with_result=False) for j in waiting.values()))
            for index, job in zip(list(waiting), states, strict=True):
                if job.state.terminal:
                    full = await queue.get(waiting.pop(index))
                    item = BatchItem(
                        index=index, job_id=full.id, state=full.state, result=full.result, error=full.error
                    )
                    yield to_proto(item, pb.BatchItem)
            if waiting:
                await asyncio.sleep(self.services.settings.sse_interval)

    @unary
    async def SubmitPlan(self, request: pb.PlanRequest, context: Any, caller: Caller) -> pb.JobCreated:
        """Enqueue a plan at once (no queue deadline; ``options.timeout`` bounds its compute)."""
        _, job_id = await self.submission.one(request, caller, context, kind="plan", model=PlanRequest)
        return pb.JobCreated(id=job_id, state=JobState.QUEUED.value)

    @unary
    async def ListRobots(self, request: pb.ListRobotsRequest, context: Any, caller: Caller) -> pb.RobotList:
        robots = await self.services.catalog().all(caller.tenant, fresh=True)
        return pb.RobotList(robots=[to_proto(r, pb.RobotPublic) for r in robots])

    @unary
    async def RegisterRobot(self, request: pb.RobotRegister, context: Any, caller: Caller) -> pb.RobotPublic:
        """The HTTP route's path (`RobotCatalog.register`): no built-in name, the key's count and bytes reserved
        atomically, validated by a worker."""
        settings = self.services.settings
        if request.ByteSize() > settings.max_robot_bytes:
            raise PayloadTooLarge(
                f"{request.ByteSize()} bytes, more than MANI_MAX_ROBOT_BYTES={settings.max_robot_bytes}"
            )
        body = await self.submission.validate(request, RobotRegister)
        robot = await self.services.catalog().register(
            body, caller.tenant, limits=settings.robot_limits(), timeout=settings.robot_register_timeout
        )
        return to_proto(robot, pb.RobotPublic)
