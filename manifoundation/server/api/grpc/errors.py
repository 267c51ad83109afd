"""The error vocabulary's gRPC status codes, and the one translation of an exception into a gRPC status.

Every `manifoundation.contract.ErrorType` has one code here (`GRPC_CODE`, tested complete). An exception becomes an
`ErrorBody` through the HTTP side's own translation (`manifoundation.server.api.errors.from_exception`: queue errors,
pydantic's `ValidationError` with each field and problem, ...), so both transports classify an error the same way; only
the last step differs. A failed call carries, besides its code and message:

- ``grpc-status-details-bin``: a ``google.rpc.Status`` with an ``ErrorInfo`` (``reason``: the ErrorType name),
  a ``BadRequest`` (each field and problem) for a validation error, and a ``RetryInfo`` (the retry delay) for
  ``RESOURCE_EXHAUSTED`` / ``UNAVAILABLE`` answers that have one (grpcurl and every gRPC stack read these);
- ``mani-error-bin``: the same error as a ``manifoundation.v1.ErrorBody`` (the HTTP answer's shape).
"""

from __future__ import annotations

import math
from typing import NoReturn

import grpc
from google.protobuf import any_pb2, duration_pb2
from google.rpc import code_pb2, error_details_pb2, status_pb2

from manifoundation.contract import ErrorBody, ErrorType
from manifoundation.contract.protos import metadata as keys
from manifoundation.contract.protos.v1 import manifoundation_pb2 as pb
from manifoundation.server.api import errors as http_errors

DOMAIN = keys.DOMAIN
DETAILS_KEY = keys.STATUS_DETAILS
ERROR_KEY = keys.ERROR

C = grpc.StatusCode
GRPC_CODE: dict[ErrorType, grpc.StatusCode] = {
    ErrorType.BAD_REQUEST: C.INVALID_ARGUMENT,
    ErrorType.UNAUTHORIZED: C.UNAUTHENTICATED,
    ErrorType.NOT_FOUND: C.NOT_FOUND,
    ErrorType.UNKNOWN_HAND: C.NOT_FOUND,
    ErrorType.METHOD_NOT_ALLOWED: C.UNIMPLEMENTED,
    ErrorType.REQUEST_TIMEOUT: C.DEADLINE_EXCEEDED,
    ErrorType.CONFLICT: C.FAILED_PRECONDITION,
    ErrorType.CANCELLED: C.CANCELLED,
    ErrorType.RESULT_EXPIRED: C.NOT_FOUND,
    ErrorType.PAYLOAD_TOO_LARGE: C.RESOURCE_EXHAUSTED,
    ErrorType.UNSUPPORTED_MEDIA_TYPE: C.INVALID_ARGUMENT,
    ErrorType.VALIDATION_ERROR: C.INVALID_ARGUMENT,
    ErrorType.ROBOT_INVALID: C.INVALID_ARGUMENT,
    ErrorType.INFEASIBLE_WAYPOINT: C.INVALID_ARGUMENT,
    ErrorType.NO_PATH_FOUND: C.INVALID_ARGUMENT,
    ErrorType.RATE_LIMITED: C.RESOURCE_EXHAUSTED,
    ErrorType.QUEUE_FULL: C.RESOURCE_EXHAUSTED,
    ErrorType.INTERNAL_ERROR: C.INTERNAL,
    ErrorType.WORKER_LOST: C.INTERNAL,
    ErrorType.UNAVAILABLE: C.UNAVAILABLE,
    ErrorType.QUEUE_SHUTDOWN: C.UNAVAILABLE,
    ErrorType.MODEL_UNAVAILABLE: C.UNAVAILABLE,
    ErrorType.DEADLINE_EXCEEDED: C.DEADLINE_EXCEEDED,
}
"""The gRPC code of each error type (409 Conflict reads FAILED_PRECONDITION: the name or the quota is taken)."""


class JobFailed(Exception):
    """A job ended without a result; the call answers with the job's own error."""

    def __init__(self, error: ErrorBody, job_id: str) -> None:
        super().__init__(error.error)
        self.error = error
        self.job_id = job_id


def code_of(error: ErrorBody) -> grpc.StatusCode:
    """The gRPC code of an error (INTERNAL for a type this version does not know)."""
    kind = error.kind
    return GRPC_CODE[kind] if kind is not None else C.INTERNAL


def translate(exc: BaseException) -> tuple[ErrorBody, float | None]:
    """Any exception an RPC raises → its error body and retry delay (s, None: none)."""
    if isinstance(exc, JobFailed):
        return exc.error, None
    api = http_errors.from_exception(exc) if isinstance(exc, Exception) else http_errors.ApiError("internal error")
    retry = api.headers.get("Retry-After")
    return api.body(), float(retry) if retry is not None else None


def trailers(error: ErrorBody, retry_after: float | None = None) -> tuple[tuple[str, str | bytes], ...]:
    """The trailing metadata of a failed call: the rich status details and our own ErrorBody."""
    code = code_of(error)
    details = [error_details_pb2.ErrorInfo(reason=error.type, domain=DOMAIN)]
    if error.detail:
        violations = [
            error_details_pb2.BadRequest.FieldViolation(field=f.field, description=f.problem) for f in error.detail
        ]
        details.append(error_details_pb2.BadRequest(field_violations=violations))
    if retry_after is not None and math.isfinite(retry_after):
        seconds = max(0.0, retry_after)
        delay = duration_pb2.Duration(seconds=int(seconds), nanos=int((seconds % 1) * 1e9))
        details.append(error_details_pb2.RetryInfo(retry_delay=delay))
    packed = []
    for detail in details:
        wrapped = any_pb2.Any()
        wrapped.Pack(detail)
        packed.append(wrapped)
    status = status_pb2.Status(code=getattr(code_pb2, code.name), message=error.error, details=packed)
    body = pb.ErrorBody(
        error=error.error,
        type=error.type,
        detail=[pb.FieldError(field=f.field, problem=f.problem) for f in error.detail or []],
    )
    return (DETAILS_KEY, status.SerializeToString()), (ERROR_KEY, body.SerializeToString())


async def abort(
    context: grpc.aio.ServicerContext, exc: BaseException, extra: tuple[tuple[str, str], ...] = ()
) -> NoReturn:
    """End the call with the status ``exc`` translates to (raises, as `ServicerContext.abort` does); ``extra``:
    more trailing metadata (the reported versions)."""
    error, retry_after = translate(exc)
    metadata = trailers(error, retry_after) + extra
    job_id = exc.job_id if isinstance(exc, JobFailed) else _job_id_of(exc)
    if job_id:
        metadata += ((keys.JOB_ID, job_id),)
    await context.abort(code_of(error), error.error, trailing_metadata=metadata)
    raise AssertionError("unreachable: abort raises")  # pragma: no cover


def _job_id_of(exc: BaseException) -> str | None:
    """The job an `ApiError` names in its ``X-Job-ID`` header (e.g. a synchronous wait cut off by a shutdown)."""
    if isinstance(exc, http_errors.ApiError):
        for name, value in exc.headers.items():
            if name.lower() == keys.JOB_ID:
                return value
    return None
