"""`GrpcJob` and `AsyncGrpcJob`: the handles `GrpcClient.job` and `AsyncGrpcClient.job` return.

They are `Job` and `AsyncJob` (`manifoundation.sdk._api`, `manifoundation.sdk._async_api`): the same methods
(``status``, ``cancel``, ``wait``, ``events``, ``plan_result``, ``finished``) and logic; over gRPC a job is followed
on its ``WatchJob`` stream and read once more when the stream ended before the job did, or its last message came
without the answer (`manifoundation.sdk.tracking.settled`). The names stay for their ``repr`` and for code that
imports them.
"""

from __future__ import annotations

from manifoundation.sdk._api import Job
from manifoundation.sdk._async_api import AsyncJob

__all__ = ["AsyncGrpcJob", "GrpcJob"]


class GrpcJob(Job):
    """A queued synthesis or plan over gRPC: the calls of `manifoundation.sdk.Job`."""


class AsyncGrpcJob(AsyncJob):
    """A queued synthesis or plan over gRPC, awaited: the calls of `manifoundation.sdk.AsyncJob`."""
