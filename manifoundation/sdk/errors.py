"""The SDK's exception tree, built from the service's one error shape ``{error, type, detail}``.

::

    ManiError                     anything this SDK raises on purpose
    ├── RequestError              the service (or the SDK, before sending) rejected a request
    │   ├── ValidationError       422 / 413 / 400, or local validation: ``detail`` names field and problem
    │   ├── Unauthorized          401 / 403: missing or wrong API key
    │   ├── NotFound              404: unknown job, batch or hand
    │   ├── RateLimited           429: queue full or rate limit; ``retry_after`` seconds
    │   └── ServerError           5xx (503: shutting down or not ready), or an unreadable answer
    ├── Unreachable               no answer at all: connection refused, DNS, connection reset
    ├── TimeoutError              waited longer than the caller allowed (also a builtin ``TimeoutError``)
    ├── JobFailed                 a job ended failed, cancelled or expired; ``job`` and ``error`` say why
    │   └── JobExpired            its deadline passed (also a TimeoutError)
    ├── IncompatibleService       the service speaks another major version of the contract
    ├── MissingExtra              an optional part ([grpc], [view], [mesh]) is not installed (an ImportError)
    └── NeedsHttp                 the call has no gRPC counterpart: use `Client`/`AsyncClient` (a NotImplementedError)

    ContractWarning (a UserWarning): the service's contract is a newer minor version than this SDK's
"""

from __future__ import annotations

import builtins
from typing import Any, TypeVar

import pydantic

from manifoundation.contract import ErrorBody, ErrorType, FieldError, JobPublic, JobState
from manifoundation.contract.validation import field_errors, summary

ModelT = TypeVar("ModelT", bound=pydantic.BaseModel)


class ManiError(Exception):
    """Base of every error the SDK raises."""


class RequestError(ManiError):
    """A request was rejected; ``status_code`` is None when the SDK rejected it before sending.

    Attributes:
        message: the service's human-readable message.
        type: the service's machine-readable error class (e.g. ``"ValidationError"``).
        detail: one `FieldError` per problem, when the service gave them.
        status_code: the HTTP status, or None.
    """

    def __init__(
        self,
        message: str,
        *,
        type: str | None = None,
        detail: list[FieldError] | None = None,
        status_code: int | None = None,
    ) -> None:
        super().__init__(message)
        self.message = message
        self.type = type or self.__class__.__name__
        self.detail = list(detail or [])
        self.status_code = status_code

    @property
    def body(self) -> ErrorBody:
        """The error in the contract's shape."""
        return ErrorBody(error=self.message, type=self.type, detail=self.detail or None)

    def __str__(self) -> str:
        status = f"[{self.status_code}] " if self.status_code is not None else ""
        lines = [f"{status}{self.message}"]
        lines += [f"  {d.field}: {d.problem}" for d in self.detail[1:]] if len(self.detail) > 1 else []
        return "\n".join(lines)


class ValidationError(RequestError):
    """The input is invalid (HTTP 422/413/400, or checked locally before sending)."""


class Unauthorized(RequestError):
    """The API key is missing or not accepted (HTTP 401/403)."""


class NotFound(RequestError):
    """No such job, batch or hand (HTTP 404)."""


class RateLimited(RequestError):
    """The service is busy (HTTP 429); try again after ``retry_after`` seconds."""

    def __init__(self, message: str, *, retry_after: float | None = None, **kwargs: object) -> None:
        super().__init__(message, **kwargs)  # type: ignore[arg-type]
        self.retry_after = retry_after


class ServerError(RequestError):
    """The service failed or is unavailable (HTTP 5xx), or answered something unreadable."""

    def __init__(self, message: str, *, retry_after: float | None = None, **kwargs: object) -> None:
        super().__init__(message, **kwargs)  # type: ignore[arg-type]
        self.retry_after = retry_after


class Unreachable(ManiError):
    """The service could not be reached (after the configured retries)."""


class TimeoutError(ManiError, builtins.TimeoutError):
    """An operation took longer than the caller allowed (a job may still be running: see ``job_id``)."""

    def __init__(self, message: str, *, job_id: str | None = None) -> None:
        super().__init__(message)
        self.job_id = job_id


class JobFailed(ManiError):
    """A job ended without a result: failed, cancelled or expired.

    Attributes:
        job_id: the job.
        state: its final state (a `JobState`).
        error: the job's error in the contract's shape, when it has one.
        job: the job as the service last showed it, when the SDK read it.
    """

    def __init__(
        self, job_id: str, state: JobState, error: ErrorBody | None = None, job: JobPublic | None = None
    ) -> None:
        self.job_id = job_id
        self.state = state
        self.error = error
        self.job = job
        why = f": {error.type}: {error.error}" if error is not None else ""
        super().__init__(f"job {job_id} {state.value}{why}")

    @classmethod
    def of(
        cls, job_id: str, state: JobState, error: ErrorBody | None = None, job: JobPublic | None = None
    ) -> JobFailed:
        """The error for a job that ended without a result: a `JobExpired` when its deadline passed."""
        if state is JobState.EXPIRED and error is not None and error.type == "DeadlineExceeded":
            return JobExpired(job_id, state, error, job)
        return cls(job_id, state, error, job)

    @classmethod
    def from_job(cls, job: JobPublic) -> JobFailed:
        """The error for a job that ended without a result."""
        return cls.of(job.id, job.state, job.error, job)


class JobExpired(JobFailed, TimeoutError):  # type: ignore[misc]  # job_id: str here, str | None in TimeoutError
    """A job whose deadline (the request's ``timeout``) passed before it ended: both a `JobFailed` and a
    `TimeoutError`, so ``except TimeoutError`` catches it whichever side noticed the deadline first, the caller's
    wait or the service."""

    def __init__(
        self, job_id: str, state: JobState, error: ErrorBody | None = None, job: JobPublic | None = None
    ) -> None:
        JobFailed.__init__(self, job_id, state, error, job)
        self.job_id = job_id  # TimeoutError's __init__ (next in the MRO) left it None


class IncompatibleService(ManiError):
    """The service's contract version cannot be spoken by this SDK (another major version, or unreadable).

    Attributes:
        service_contract: the contract version the service reported.
        client_contract: this SDK's contract version.
        service_version: the service's own version, when it reported one.
    """

    def __init__(self, service_contract: str, client_contract: str, service_version: str | None, where: str) -> None:
        self.service_contract = service_contract
        self.client_contract = client_contract
        self.service_version = service_version
        server = f" (service {service_version})" if service_version else ""
        super().__init__(
            f"{where} speaks contract {service_contract!r}{server}, this client contract {client_contract}: "
            f"another major version cannot be read safely; install the manifoundation-client that matches the "
            f"service (docs/compatibility.md)"
        )


class MissingExtra(ManiError, ImportError):
    """A call needs an optional part of the client distribution that is not installed; ``extra`` names it."""

    def __init__(self, message: str, *, extra: str) -> None:
        super().__init__(message)
        self.extra = extra


class NeedsHttp(ManiError, NotImplementedError):
    """A client call the gRPC service has no RPC for (e.g. ``delete_robot``): make it with `Client` or
    `AsyncClient` over HTTP. Raised before anything is sent.

    Attributes:
        method: the client method called (e.g. ``"delete_robot"``).
        reason: why gRPC cannot serve it.
    """

    def __init__(self, method: str, reason: str) -> None:
        super().__init__(f"{method}() needs the HTTP transport ({reason}): use Client or AsyncClient for it")
        self.method = method
        self.reason = reason


class ContractWarning(UserWarning):
    """The service's contract is a newer minor version: its answers may carry what this SDK ignores."""


_BY_TYPE: dict[ErrorType, type[RequestError]] = {
    ErrorType.BAD_REQUEST: ValidationError,
    ErrorType.UNAUTHORIZED: Unauthorized,
    ErrorType.NOT_FOUND: NotFound,
    ErrorType.UNKNOWN_HAND: NotFound,
    ErrorType.PAYLOAD_TOO_LARGE: ValidationError,
    ErrorType.UNSUPPORTED_MEDIA_TYPE: ValidationError,
    ErrorType.VALIDATION_ERROR: ValidationError,
    ErrorType.ROBOT_INVALID: ValidationError,
    ErrorType.RATE_LIMITED: RateLimited,
    ErrorType.QUEUE_FULL: RateLimited,
}
"""The contract's error types mapped back to this SDK's classes (the one place); other types: by status."""

_BY_STATUS: dict[int, type[RequestError]] = {
    400: ValidationError,
    401: Unauthorized,
    403: Unauthorized,
    404: NotFound,
    413: ValidationError,
    422: ValidationError,
    429: RateLimited,
}


def error_for(
    status_code: int, body: ErrorBody | None, text: str = "", retry_after: float | None = None
) -> RequestError:
    """The exception for an error answer: class by the body's `ErrorType` (by the status for a type this
    version does not know, or no contract body), message/type/detail from the body.

    Args:
        status_code: the HTTP status (≥ 400).
        body: the decoded error body, when the answer had one in the contract's shape.
        text: the raw body text, used as the message when there is no contract body.
        retry_after: seconds from the Retry-After header.
    """
    kind = body.kind if body is not None else None
    by_status = _BY_STATUS.get(status_code, ServerError if status_code >= 500 else RequestError)
    cls = _BY_TYPE.get(kind, ServerError if status_code >= 500 else by_status) if kind is not None else by_status
    message = body.error if body else (text.strip()[:500] or f"HTTP {status_code}")
    kwargs: dict[str, object] = {
        "type": body.type if body else None,
        "detail": body.detail if body else None,
        "status_code": status_code,
    }
    if cls in (RateLimited, ServerError):
        kwargs["retry_after"] = retry_after
    return cls(message, **kwargs)  # type: ignore[arg-type]


def local_validation_error(exc: pydantic.ValidationError, root: str = "") -> ValidationError:
    """The SDK's `ValidationError` for input that failed the contract before it was sent.

    Args:
        exc: pydantic's error.
        root: where the validated part sits in the request (e.g. ``"object"``), so that field paths read as
            the service would write them (``object.points``).
    """
    detail = field_errors(exc, root=root)
    message = f"invalid {root or 'request'}: {summary(detail)}"
    return ValidationError(message, type=ErrorType.VALIDATION_ERROR.value, detail=detail)


def checked(cls: type[ModelT], root: str, **fields: Any) -> ModelT:
    """``cls(**fields)``, raising the SDK's `ValidationError` (fields under ``root``) instead of pydantic's."""
    try:
        return cls(**fields)
    except pydantic.ValidationError as exc:
        raise local_validation_error(exc, root) from exc
