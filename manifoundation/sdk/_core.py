"""The I/O-free half of the HTTP transports: building requests, reading answers, deciding retries.

`HttpTransport` (`Client`'s) and `AsyncHttpTransport` (`AsyncClient`'s) share everything here and differ only in
how they send (the httpx pattern); what a call means (waiting, polling, arguments) is the clients' one surface
(`manifoundation.sdk._api`). Nothing in this module opens a connection or sleeps, so all of it is testable with
plain values.

Why one module: every HTTP request the SDK can make is built and read here, once for both transports; each part
is a few lines.
"""

from __future__ import annotations

import os
import random
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Generic, Literal, TypedDict, TypeVar

import httpx
import pydantic
from pydantic import BaseModel

from manifoundation.contract import (
    BatchCreate,
    BatchPublic,
    ErrorBody,
    HealthPublic,
    JobCreated,
    JobList,
    JobPublic,
    JobState,
    PlanRequest,
    ReadyPublic,
    RobotList,
    RobotPreview,
    RobotPublic,
    RobotRegister,
    SynthesisRequest,
    SynthesisResult,
)
from manifoundation.contract.codec import JSON, MSGPACK, DecodeError, decode_body, dump_model, media_type
from manifoundation.contract.common import ANSWER_CONTEXT
from manifoundation.sdk.compat import VersionCheck
from manifoundation.sdk.errors import (
    JobFailed,
    ServerError,
    TimeoutError,
    Unreachable,
    error_for,
    local_validation_error,
)
from manifoundation.sdk.retry import (
    DEFAULT_RETRY,
    IDEMPOTENT_METHODS,
    MAYBE_SENT,
    NOT_SENT,
    RETRY_STATUSES,
    RETRY_STATUSES_IDEMPOTENT,
    RetryPolicy,
    parse_retry_after,
)

T = TypeVar("T")
ModelT = TypeVar("ModelT", bound=BaseModel)
Encoding = Literal["msgpack", "json"]

DEFAULT_BASE_URL = "http://127.0.0.1:8000"
URL_VARIABLE = "MANI_URL"
"""The environment variable naming the service when a client is given no URL (the `mani` CLI reads it too)."""
USER_AGENT = "manifoundation-sdk/0.1"
# Seconds added to the server-side wait of /v1/synthesize before the HTTP read gives up.
READ_MARGIN_S = 10.0
# A finished job's error type → its state (anything else: failed).
_ERROR_STATES = {
    "Cancelled": JobState.CANCELLED,
    "DeadlineExceeded": JobState.EXPIRED,
    "ResultExpired": JobState.EXPIRED,
}


def default_base_url() -> str:
    """The service a client given no URL talks to: ``MANI_URL`` when set (and not empty), else the local default."""
    return os.environ.get(URL_VARIABLE) or DEFAULT_BASE_URL


class HttpSettings(TypedDict, total=False):
    """The keyword settings of the HTTP clients (see `BaseClient`)."""

    timeout: float | httpx.Timeout
    retries: RetryPolicy | int
    encoding: Encoding
    headers: dict[str, str] | None
    poll_interval: float


@dataclass
class Call(Generic[T]):
    """One API call: the request to send and how to read its answer."""

    request: httpx.Request
    parse: Callable[[httpx.Response], T]
    retry: bool = True


class BaseClient:
    """Configuration and all the I/O-free logic of `HttpTransport` and `AsyncHttpTransport` (`Client`'s and
    `AsyncClient`'s settings).

    Args:
        base_url: where the service listens, e.g. ``"http://127.0.0.1:8000"``; None (default): the environment's
            ``MANI_URL``, else ``DEFAULT_BASE_URL``.
        api_key: bearer token sent as ``Authorization: Bearer ...`` (None: no auth).
        timeout: default timeout for one HTTP exchange, seconds (or an ``httpx.Timeout``).
        retries: a `RetryPolicy`, or the number of retries with the default backoff.
        encoding: ``"msgpack"`` (default: typed binary arrays, smaller and faster) or ``"json"``.
        headers: extra headers sent with every request.
        poll_interval: largest pause between two status polls when waiting on a job or batch, seconds.
    """

    def __init__(
        self,
        base_url: str | None = None,
        api_key: str | None = None,
        *,
        timeout: float | httpx.Timeout = 30.0,
        retries: RetryPolicy | int = DEFAULT_RETRY,
        encoding: Encoding = "msgpack",
        headers: dict[str, str] | None = None,
        poll_interval: float = 1.0,
    ) -> None:
        if encoding not in ("msgpack", "json"):
            raise ValueError(f"encoding must be 'msgpack' or 'json', not {encoding!r}")
        self.base_url = str(base_url or default_base_url()).rstrip("/")
        self.api_key = api_key
        self.timeout = timeout if isinstance(timeout, httpx.Timeout) else httpx.Timeout(timeout)
        self.retry_policy = retries if isinstance(retries, RetryPolicy) else RetryPolicy(max_retries=int(retries))
        self.encoding: Encoding = encoding
        self.poll_interval = poll_interval
        self._media = MSGPACK if encoding == "msgpack" else JSON
        self._headers = {"User-Agent": USER_AGENT, "Accept": self._media, **(headers or {})}
        if api_key:
            self._headers["Authorization"] = f"Bearer {api_key}"
        self._rng = random.Random()
        self.versions = VersionCheck(self.base_url)

    def __repr__(self) -> str:
        return f"{type(self).__name__}(base_url={self.base_url!r}, encoding={self.encoding!r})"

    # ---- requests -------------------------------------------------------------------------------------------

    def build_request(
        self,
        method: str,
        path: str,
        *,
        body: BaseModel | None = None,
        params: dict[str, Any] | None = None,
        read_timeout: float | None = None,
        accept: str | None = None,
    ) -> httpx.Request:
        """An ``httpx.Request`` to ``base_url + path`` with our headers, body encoding and timeouts."""
        headers = dict(self._headers)
        content = None
        if body is not None:
            content = dump_model(body, self._media)
            headers["Content-Type"] = self._media
        if accept is not None:
            headers["Accept"] = accept
        timeout = self.timeout
        if read_timeout is not None:
            timeout = httpx.Timeout(
                connect=self.timeout.connect, read=read_timeout, write=self.timeout.write, pool=self.timeout.pool
            )
        clean = {k: v for k, v in (params or {}).items() if v is not None}
        return httpx.Request(
            method,
            self.base_url + path,
            params=clean or None,
            headers=headers,
            content=content,
            extensions={"timeout": timeout.as_dict()},
        )

    # ---- answers --------------------------------------------------------------------------------------------

    def parse(self, response: httpx.Response, model: type[ModelT]) -> ModelT:
        """Validate a 2xx answer into ``model``; raise the matching `RequestError` for any other."""
        self.raise_for_status(response)
        try:
            data = decode_body(response.content, response.headers.get("content-type"))
            return model.model_validate(data, context=ANSWER_CONTEXT)
        except (DecodeError, pydantic.ValidationError) as exc:
            raise ServerError(
                f"unreadable {model.__name__} from {response.request.url.path}: {exc}",
                type="ProtocolError",
                status_code=response.status_code,
            ) from exc

    def raise_for_status(self, response: httpx.Response) -> None:
        """Raise the SDK error for a non-2xx answer, built from its ``{error, type, detail}`` body, or
        `IncompatibleService` for any answer of a service that speaks another major version of the contract."""
        self.versions.see(response.headers.get)
        if response.is_success:
            return
        body: ErrorBody | None = None
        try:
            body = ErrorBody.model_validate(
                decode_body(response.content, response.headers.get("content-type")), context=ANSWER_CONTEXT
            )
        except (DecodeError, pydantic.ValidationError):
            body = _fastapi_detail(response)
        retry_after = parse_retry_after(response.headers.get("retry-after"))
        raise error_for(response.status_code, body, _text(response), retry_after)

    # ---- retries --------------------------------------------------------------------------------------------

    def retry_delay(
        self, retry: int, request: httpx.Request, response: httpx.Response | None = None, exc: Exception | None = None
    ) -> float | None:
        """Seconds to wait before retrying, or None to stop (then the answer or error stands).

        Args:
            retry: retries done so far.
            request: the request that was sent.
            response: its answer, when one came.
            exc: the transport error, when none came.
        """
        if retry >= self.retry_policy.max_retries:
            return None
        idempotent = request.method in IDEMPOTENT_METHODS
        if response is not None:
            statuses = RETRY_STATUSES_IDEMPOTENT if idempotent else RETRY_STATUSES
            if response.status_code not in statuses:
                return None
            return self.retry_policy.delay(retry, parse_retry_after(response.headers.get("retry-after")), self._rng)
        if isinstance(exc, NOT_SENT) or (idempotent and isinstance(exc, MAYBE_SENT)):
            return self.retry_policy.delay(retry, None, self._rng)
        return None

    def job_ended(self, job_id: str, response: httpx.Response) -> JobFailed:
        """`JobFailed` for a synchronous answer that carries a finished job's error (``X-Job-ID`` + error body)."""
        try:
            body = ErrorBody.model_validate(
                decode_body(response.content, response.headers.get("content-type")), context=ANSWER_CONTEXT
            )
        except (DecodeError, pydantic.ValidationError):
            body = ErrorBody(error=_text(response)[:500] or f"HTTP {response.status_code}", type="JobFailed")
        state = _ERROR_STATES.get(body.type, JobState.FAILED)
        return JobFailed.of(job_id, state, body)

    def transport_error(self, request: httpx.Request, exc: Exception) -> Exception:
        """The SDK error for a transport failure that is not retried any more."""
        if isinstance(exc, httpx.TimeoutException) and not isinstance(exc, httpx.ConnectTimeout | httpx.PoolTimeout):
            return TimeoutError(f"{request.method} {request.url.path}: no answer in time ({exc})")
        return Unreachable(f"cannot reach {self.base_url} ({type(exc).__name__}: {exc})")

    # ---- the calls ------------------------------------------------------------------------------------------

    def _call_synthesize(self, request: SynthesisRequest) -> Call[SynthesisResult | JobCreated]:
        http = self.build_request(
            "POST", "/v1/synthesize", body=request, read_timeout=request.options.timeout + READ_MARGIN_S
        )

        def parse(response: httpx.Response) -> SynthesisResult | JobCreated:
            if response.status_code == 202:
                return self.parse(response, JobCreated)
            job_id = response.headers.get("x-job-id")
            if not response.is_success and job_id and response.status_code not in (429, 503):
                raise self.job_ended(job_id, response)  # the job ran and ended without a result
            return self.parse(response, SynthesisResult)

        return Call(http, parse)

    def _call_submit(self, request: SynthesisRequest) -> Call[JobCreated]:
        return self._model_call("POST", "/v1/jobs", JobCreated, body=request)

    def _call_submit_plan(self, request: PlanRequest) -> Call[JobCreated]:
        return self._model_call("POST", "/v1/plans", JobCreated, body=request)

    def _call_job(self, job_id: str) -> Call[JobPublic]:
        return self._model_call("GET", f"/v1/jobs/{job_id}", JobPublic)

    def _call_cancel(self, job_id: str) -> Call[JobPublic]:
        return self._model_call("DELETE", f"/v1/jobs/{job_id}", JobPublic)

    def _call_submit_batch(self, requests: list[SynthesisRequest]) -> Call[str]:
        try:
            body = BatchCreate(requests=requests)
        except pydantic.ValidationError as exc:
            raise local_validation_error(exc) from exc
        http = self.build_request("POST", "/v1/batches", body=body)

        def parse(response: httpx.Response) -> str:
            data = self._plain(response)
            batch_id = data.get("id", data.get("batch_id")) if isinstance(data, dict) else None
            if not isinstance(batch_id, str):
                raise ServerError("batch answer carries no id", type="ProtocolError", status_code=response.status_code)
            return batch_id

        return Call(http, parse)

    def _call_batch(self, batch_id: str, offset: int = 0, limit: int = 100) -> Call[BatchPublic]:
        params = {"offset": offset, "limit": limit}
        return self._model_call("GET", f"/v1/batches/{batch_id}", BatchPublic, params=params)

    def _call_jobs(self, limit: int = 50) -> Call[list[JobPublic]]:
        return self._list_call("/v1/jobs", JobList, {"limit": limit})

    def _call_robots(self) -> Call[list[RobotPublic]]:
        return self._list_call("/v1/robots", RobotList)

    def _list_call(
        self, path: str, model: type[JobList] | type[RobotList], params: dict[str, Any] | None = None
    ) -> Call[Any]:
        """A list answer in the contract's shape (`JobList`, `RobotList`), unwrapped to its one list."""
        inner = self._model_call("GET", path, model, params=params)

        def parse(response: httpx.Response) -> list[Any]:
            answer = inner.parse(response)
            return list(answer.jobs if isinstance(answer, JobList) else answer.robots)

        return Call(inner.request, parse)

    def _plain(self, response: httpx.Response) -> Any:
        """The decoded (not validated) content of a 2xx answer."""
        self.raise_for_status(response)
        try:
            return decode_body(response.content, response.headers.get("content-type"))
        except DecodeError as exc:
            raise ServerError(f"unreadable answer: {exc}", type="ProtocolError") from exc

    def _call_robot(self, name: str) -> Call[RobotPublic]:
        return self._model_call("GET", f"/v1/robots/{name}", RobotPublic)

    def _call_register_robot(self, body: RobotRegister) -> Call[RobotPublic]:
        return self._model_call("POST", "/v1/robots", RobotPublic, body=body)

    def _call_robot_preview(self, name: str) -> Call[RobotPreview]:
        return self._model_call("GET", f"/v1/robots/{name}/preview", RobotPreview)

    def _call_delete_robot(self, name: str) -> Call[None]:
        def parse(response: httpx.Response) -> None:
            self.raise_for_status(response)

        return Call(self.build_request("DELETE", f"/v1/robots/{name}"), parse)

    def _call_health(self) -> Call[HealthPublic]:
        return self._model_call("GET", "/healthz", HealthPublic)

    def _call_ready(self) -> Call[ReadyPublic]:
        http = self.build_request("GET", "/readyz")

        def parse(response: httpx.Response) -> ReadyPublic:
            if response.status_code == 503:  # not ready is an answer, not an error, when it has the shape
                try:
                    data = decode_body(response.content, response.headers.get("content-type"))
                    return ReadyPublic.model_validate(data, context=ANSWER_CONTEXT)
                except (DecodeError, pydantic.ValidationError):
                    pass
            return self.parse(response, ReadyPublic)

        return Call(http, parse, retry=False)

    def _model_call(
        self,
        method: str,
        path: str,
        model: type[ModelT],
        *,
        body: BaseModel | None = None,
        params: dict[str, Any] | None = None,
    ) -> Call[ModelT]:
        return Call(self.build_request(method, path, body=body, params=params), lambda r: self.parse(r, model))


def _text(response: httpx.Response) -> str:
    try:
        return response.text
    except (UnicodeDecodeError, httpx.ResponseNotRead):
        return ""


def _fastapi_detail(response: httpx.Response) -> ErrorBody | None:
    """Read FastAPI's own ``{"detail": ...}`` shape (e.g. a 405 from the framework) as an `ErrorBody`."""
    if media_type(response.headers.get("content-type")) != JSON:
        return None
    try:
        data = response.json()
    except ValueError:
        return None
    if isinstance(data, dict) and isinstance(data.get("detail"), str):
        return ErrorBody(error=data["detail"], type=f"HTTP{response.status_code}")
    return None
