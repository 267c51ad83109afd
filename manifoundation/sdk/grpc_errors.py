"""A failed gRPC call → the SDK's exceptions (`manifoundation.sdk.errors`), the same ones the HTTP client raises.

The service sends each error's contract body in the trailers (``mani-error-bin``: the HTTP answer's
``{error, type, detail}``) and the retry delay in ``google.rpc.RetryInfo``; the class comes from the body's type as
over HTTP (`errors.error_for`), else from the gRPC code. A call that names its job in the trailers (``x-job-id``)
ran a job that ended without a result: `JobFailed`. A call that the service never answered is `Unreachable`
(UNAVAILABLE) or `TimeoutError` (the call's deadline passed). ``status_code`` stays None: there is no HTTP status.
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any

import grpc
from google.protobuf.message import DecodeError
from google.rpc import error_details_pb2, status_pb2

from manifoundation.contract import ErrorBody, FieldError, JobState
from manifoundation.contract.protos import metadata as keys
from manifoundation.contract.protos.v1 import manifoundation_pb2 as pb
from manifoundation.sdk.errors import JobFailed, ManiError, TimeoutError, Unreachable, error_for

C = grpc.StatusCode
# The HTTP status each code stands for, to pick the class as `error_for` does when the body's type is unknown.
_STATUS_OF_CODE = {
    C.INVALID_ARGUMENT: 400, C.OUT_OF_RANGE: 400, C.UNAUTHENTICATED: 401, C.PERMISSION_DENIED: 403,
    C.NOT_FOUND: 404, C.ALREADY_EXISTS: 409, C.FAILED_PRECONDITION: 409, C.RESOURCE_EXHAUSTED: 429,
    C.UNIMPLEMENTED: 501, C.UNAVAILABLE: 503, C.DEADLINE_EXCEEDED: 504,
}  # fmt: skip
_JOB_STATES = {"Cancelled": JobState.CANCELLED, "DeadlineExceeded": JobState.EXPIRED, "ResultExpired": JobState.EXPIRED}
RETRYABLE = frozenset({C.RESOURCE_EXHAUSTED, C.UNAVAILABLE})
"""Codes worth retrying when the service itself refused (its body says why: a full queue, a rate limit, shutdown)."""


def pairs(items: Iterable[Any] | None) -> dict[str, Any]:
    """Metadata as a dict with lower-case keys (None: empty)."""
    return {str(key).lower(): value for key, value in items or ()}


def _body(trailers: dict[str, Any]) -> ErrorBody | None:
    raw = trailers.get(keys.ERROR)
    if not isinstance(raw, bytes):
        return None
    try:
        message = pb.ErrorBody.FromString(raw)
    except DecodeError:
        return None
    detail = [FieldError(field=f.field, problem=f.problem) for f in message.detail]
    return ErrorBody(error=message.error, type=message.type, detail=detail or None)


def retry_after(trailers: dict[str, Any]) -> float | None:
    """Seconds from the call's ``google.rpc.RetryInfo``, when it has one."""
    raw = trailers.get(keys.STATUS_DETAILS)
    if not isinstance(raw, bytes):
        return None
    try:
        status = status_pb2.Status.FromString(raw)
    except DecodeError:
        return None
    for detail in status.details:
        info = error_details_pb2.RetryInfo()
        if detail.Unpack(info):
            return info.retry_delay.seconds + info.retry_delay.nanos / 1e9
    return None


def sent_by_service(error: grpc.RpcError) -> bool:
    """Whether the service answered the call with one of its own errors (not the channel or the deadline)."""
    return keys.ERROR in pairs(getattr(error, "trailing_metadata", lambda: None)())


def error_from(error: grpc.RpcError, where: str, job_id: str | None = None) -> ManiError:
    """The SDK's exception for a failed call.

    Args:
        error: what grpcio raised (a ``grpc.Call``: code, details, metadata).
        where: the target, for messages.
        job_id: the call's job when the initial metadata named one.
    """
    code: grpc.StatusCode = error.code()
    details: str = error.details() or ""
    trailers = pairs(error.trailing_metadata())
    body = _body(trailers)
    ended = trailers.get(keys.JOB_ID)
    if body is None:
        if code is C.UNAVAILABLE:
            return Unreachable(f"cannot reach {where} (UNAVAILABLE: {details})")
        if code is C.DEADLINE_EXCEEDED:
            return TimeoutError(f"{where}: no answer before the call's deadline ({details})", job_id=job_id)
        if code is C.CANCELLED:
            return ManiError(f"{where}: the call was cancelled ({details})")
    if isinstance(ended, str) and body is not None:
        return JobFailed.of(ended, _JOB_STATES.get(body.type, JobState.FAILED), body)
    status = _STATUS_OF_CODE.get(code, 500)
    exc = error_for(status, body, text=f"{code.name}: {details}", retry_after=retry_after(trailers))
    exc.status_code = None
    return exc
