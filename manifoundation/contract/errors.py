"""The error vocabulary: every error the service answers or a job ends with, its HTTP status and job state.

One enum, read by every side: the service maps `ErrorType.status` to the HTTP answer (and each type to a gRPC
code: ``GRPC_CODE`` in `manifoundation/server/api/grpc/errors.py`), the workers put an `ErrorType` in a failed job's
`ErrorBody`, the SDK maps it back to its exception classes. A job whose error is `CANCELLED` ends *cancelled*,
`DEADLINE_EXCEEDED` / `RESULT_EXPIRED` end *expired*, every other error ends *failed* (`ErrorType.job_state`).

Compatibility: a newer service may add members. A client that reads a type it does not know keeps the string
(`ErrorBody.type` accepts any name) and classifies the error by its HTTP status.
"""

from __future__ import annotations

from enum import StrEnum

from pydantic import Field

from manifoundation.contract.common import WireModel
from manifoundation.contract.states import JobState


class ErrorType(StrEnum):
    """Machine-readable error classes (the ``type`` of an `ErrorBody`)."""

    BAD_REQUEST = "BadRequest"
    """400: a body that is not JSON/msgpack, a bad query parameter."""
    UNAUTHORIZED = "Unauthorized"
    """401: missing or unknown API key."""
    NOT_FOUND = "NotFound"
    """404: unknown job, batch or route."""
    UNKNOWN_HAND = "UnknownHand"
    """404: the request names a hand that is neither built in nor registered by the caller."""
    METHOD_NOT_ALLOWED = "MethodNotAllowed"
    """405."""
    REQUEST_TIMEOUT = "RequestTimeout"
    """408: the body did not arrive in time."""
    CONFLICT = "Conflict"
    """409: e.g. registering a built-in hand's name."""
    CANCELLED = "Cancelled"
    """409: the job was cancelled (job state *cancelled*)."""
    RESULT_EXPIRED = "ResultExpired"
    """410: the job finished but its result was removed (job state *expired*)."""
    PAYLOAD_TOO_LARGE = "PayloadTooLarge"
    """413: the body is over the limit (the message gives it)."""
    UNSUPPORTED_MEDIA_TYPE = "UnsupportedMediaType"
    """415: a body that is neither JSON nor msgpack."""
    VALIDATION_ERROR = "ValidationError"
    """422: the input breaks the contract; ``detail`` names each field and problem."""
    ROBOT_INVALID = "RobotInvalid"
    """422: a robot description the hardened loader refused (the message names the element)."""
    INFEASIBLE_WAYPOINT = "InfeasibleWaypoint"
    """422: a plan's start, or a waypoint it did not repair, puts the object in collision (``detail`` names it)."""
    NO_PATH_FOUND = "NoPathFound"
    """422: the planner found no collision-free motion for a plan's segment in time (``detail`` names its end)."""
    RATE_LIMITED = "RateLimited"
    """429: the key's request rate is over its limit (Retry-After)."""
    QUEUE_FULL = "QueueFull"
    """429: the queue has no room (Retry-After)."""
    INTERNAL_ERROR = "InternalError"
    """500: a fault of the service; never the caller's."""
    WORKER_LOST = "WorkerLost"
    """500: the job's worker died on every delivery (the job was dead-lettered)."""
    UNAVAILABLE = "Unavailable"
    """503: shutting down, or the queue is unreachable (Retry-After)."""
    QUEUE_SHUTDOWN = "QueueShutdown"
    """503: the queue shut down before the job finished."""
    MODEL_UNAVAILABLE = "ModelUnavailable"
    """503: the request needs a trained model and none is loaded."""
    DEADLINE_EXCEEDED = "DeadlineExceeded"
    """504: the job's deadline passed (job state *expired*)."""

    @property
    def status(self) -> int:
        """The HTTP status of an answer carrying this error."""
        return _STATUS[self]

    @property
    def job_state(self) -> JobState:
        """The terminal state of a job that ends with this error."""
        if self is ErrorType.CANCELLED:
            return JobState.CANCELLED
        if self in (ErrorType.DEADLINE_EXCEEDED, ErrorType.RESULT_EXPIRED):
            return JobState.EXPIRED
        return JobState.FAILED

    @classmethod
    def parse(cls, name: str) -> ErrorType | None:
        """The member called ``name``, or None for a name this version does not know."""
        try:
            return cls(name)
        except ValueError:
            return None


_STATUS: dict[ErrorType, int] = {
    ErrorType.BAD_REQUEST: 400,
    ErrorType.UNAUTHORIZED: 401,
    ErrorType.NOT_FOUND: 404,
    ErrorType.UNKNOWN_HAND: 404,
    ErrorType.METHOD_NOT_ALLOWED: 405,
    ErrorType.REQUEST_TIMEOUT: 408,
    ErrorType.CONFLICT: 409,
    ErrorType.CANCELLED: 409,
    ErrorType.RESULT_EXPIRED: 410,
    ErrorType.PAYLOAD_TOO_LARGE: 413,
    ErrorType.UNSUPPORTED_MEDIA_TYPE: 415,
    ErrorType.VALIDATION_ERROR: 422,
    ErrorType.ROBOT_INVALID: 422,
    ErrorType.INFEASIBLE_WAYPOINT: 422,
    ErrorType.NO_PATH_FOUND: 422,
    ErrorType.RATE_LIMITED: 429,
    ErrorType.QUEUE_FULL: 429,
    ErrorType.INTERNAL_ERROR: 500,
    ErrorType.WORKER_LOST: 500,
    ErrorType.UNAVAILABLE: 503,
    ErrorType.QUEUE_SHUTDOWN: 503,
    ErrorType.MODEL_UNAVAILABLE: 503,
    ErrorType.DEADLINE_EXCEEDED: 504,
}


class FieldError(WireModel):
    """One problem with one field of the input."""

    field: str = Field(..., examples=["object.points"])
    problem: str


class ErrorBody(WireModel):
    """The one error shape of every non-2xx answer (and of a failed job).

    ``type`` is an `ErrorType` name; it is typed as a string so that a client reading a newer service's
    answer keeps a name it does not know instead of failing (`kind` gives the member, or None).
    """

    error: str = Field(..., description="Human-readable message naming the problem.")
    type: str = Field(
        ..., description="Machine-readable class (an ErrorType name), e.g. ValidationError, NotFound, RateLimited."
    )
    detail: list[FieldError] | None = None

    @property
    def kind(self) -> ErrorType | None:
        """The error's `ErrorType`, or None when this version does not know the name."""
        return ErrorType.parse(self.type)

    @property
    def status(self) -> int:
        """The HTTP status for this error (500 for a name this version does not know)."""
        kind = self.kind
        return kind.status if kind is not None else 500

    @classmethod
    def of(cls, kind: ErrorType, message: str, detail: list[FieldError] | None = None) -> ErrorBody:
        """The body for an error of a known type."""
        return cls(error=message, type=kind.value, detail=detail)
