"""The I/O-free core: retry decisions, Retry-After, error mapping, batch tracking, SSE decoding."""

from __future__ import annotations

import email.utils
import random
import time
from collections.abc import Callable
from typing import Any

import httpx
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from manifoundation.contract import BatchItem, BatchPublic, JobState
from manifoundation.contract.codec import MSGPACK, pack
from manifoundation.sdk import (
    NotFound,
    RateLimited,
    RequestError,
    RetryPolicy,
    ServerError,
    Unauthorized,
    ValidationError,
)
from manifoundation.sdk._core import BaseClient
from manifoundation.sdk.retry import parse_retry_after, poll_delays
from manifoundation.sdk.sse import iter_events
from manifoundation.sdk.tracking import BatchTracker


@given(st.integers(0, 20), st.floats(0, 1), st.one_of(st.none(), st.floats(0, 1000)))
def test_delay_is_bounded_exponential_with_jitter(retry: int, jitter: float, retry_after: float | None) -> None:
    policy = RetryPolicy(backoff=0.1, max_backoff=5.0, jitter=jitter, max_retry_after=30.0)
    delay = policy.delay(retry, retry_after, random.Random(retry))
    base = min(5.0, 0.1 * 2**retry)
    low = base * (1 - jitter)
    if retry_after is not None:
        low = max(low, min(retry_after, 30.0))
    assert low - 1e-9 <= delay <= max(base, min(retry_after or 0, 30.0)) + 1e-9


def test_delays_grow_then_cap() -> None:
    policy = RetryPolicy(backoff=0.25, max_backoff=2.0, jitter=0.0)
    assert [policy.delay(n) for n in range(5)] == [0.25, 0.5, 1.0, 2.0, 2.0]
    assert policy.delay(0, retry_after=3.0) == 3.0


def test_retry_after_seconds_and_http_date() -> None:
    assert parse_retry_after("7") == 7.0
    assert parse_retry_after(None) is None
    assert parse_retry_after("soon") is None
    now = time.time()
    header = email.utils.formatdate(now + 10, usegmt=True)
    assert 8.0 <= (parse_retry_after(header, now=now) or 0) <= 10.5


def test_poll_delays_grow_to_cap() -> None:
    delays = poll_delays(0.05, 2.0, 0.3)
    assert [next(delays) for _ in range(5)] == [0.05, 0.1, 0.2, 0.3, 0.3]


@pytest.mark.parametrize(
    ("method", "status", "retried"),
    [("POST", 429, True), ("POST", 503, True), ("POST", 502, False), ("GET", 502, True), ("GET", 500, False),
     ("POST", 422, False), ("GET", 404, False), ("DELETE", 504, True)],
)  # fmt: skip
def test_which_answers_are_retried(method: str, status: int, retried: bool) -> None:
    core = BaseClient("http://x", retries=RetryPolicy(max_retries=2))
    request = core.build_request(method, "/v1/jobs")
    response = httpx.Response(status, headers={"retry-after": "1"})
    delay = core.retry_delay(0, request, response=response)
    assert (delay is not None) is retried
    if retried:
        assert delay is not None and delay >= 1.0
    assert core.retry_delay(2, request, response=response) is None  # retries used up


def test_connection_errors_retried_only_when_safe() -> None:
    core = BaseClient("http://x")
    post, get = core.build_request("POST", "/v1/jobs"), core.build_request("GET", "/v1/jobs/1")
    refused = httpx.ConnectError("refused")
    reset = httpx.ReadError("reset")
    assert core.retry_delay(0, post, exc=refused) is not None
    assert core.retry_delay(0, post, exc=reset) is None  # may have been accepted: never duplicate a job
    assert core.retry_delay(0, get, exc=reset) is not None
    assert core.retry_delay(0, get, exc=httpx.ReadTimeout("slow")) is None


def test_requests_carry_encoding_key_and_timeouts() -> None:
    core = BaseClient("http://h:1/prefix/", api_key="k", encoding="msgpack", timeout=5.0)
    request = core.build_request("GET", "/v1/jobs", params={"limit": 3, "skip": None}, read_timeout=42.0)
    assert str(request.url) == "http://h:1/prefix/v1/jobs?limit=3"
    assert request.headers["authorization"] == "Bearer k"
    assert request.headers["accept"] == MSGPACK
    assert request.extensions["timeout"]["read"] == 42.0
    assert request.extensions["timeout"]["connect"] == 5.0
    assert "Authorization" not in BaseClient("http://h").build_request("GET", "/").headers
    with pytest.raises(ValueError, match="encoding"):
        BaseClient(encoding="xml")  # type: ignore[arg-type]


def _answer(status: int, body: object, msgpack: bool = False, headers: dict[str, str] | None = None) -> httpx.Response:
    request = httpx.Request("GET", "http://x/v1/thing")
    if msgpack:
        return httpx.Response(
            status, content=pack(body), headers={"content-type": MSGPACK, **(headers or {})}, request=request
        )
    return httpx.Response(status, json=body, headers=headers, request=request)


@pytest.mark.parametrize(
    ("status", "cls"),
    [(422, ValidationError), (413, ValidationError), (401, Unauthorized), (404, NotFound), (429, RateLimited),
     (503, ServerError), (500, ServerError), (409, RequestError)],
)  # fmt: skip
def test_error_answers_become_the_tree(status: int, cls: type[RequestError]) -> None:
    body = {"error": "points: too few", "type": "X", "detail": [{"field": "object.points", "problem": "too few"}]}
    with pytest.raises(cls) as info:
        BaseClient().raise_for_status(_answer(status, body, msgpack=status % 2 == 0, headers={"retry-after": "3"}))
    err = info.value
    assert type(err) is cls
    assert (err.status_code, err.message, err.type) == (status, "points: too few", "X")
    assert err.detail[0].field == "object.points"
    assert err.body.detail is not None
    if isinstance(err, RateLimited | ServerError):
        assert err.retry_after == 3.0


def test_error_answers_without_the_contract_shape() -> None:
    with pytest.raises(RequestError, match="Method Not Allowed") as info:
        BaseClient().raise_for_status(_answer(405, {"detail": "Method Not Allowed"}))
    assert info.value.type == "HTTP405"
    plain = httpx.Response(502, text="bad gateway", request=httpx.Request("GET", "http://x/"))
    with pytest.raises(ServerError, match="bad gateway"):
        BaseClient().raise_for_status(plain)


def test_batch_tracker_reports_each_item_once_and_skips_quiet_pages(result_factory: Callable[..., Any]) -> None:
    tracker = BatchTracker("b", total=5, page_size=2)
    assert tracker.pending_pages() == [0, 2, 4]

    def page(offset: int, states: list[JobState], with_result: bool = True) -> BatchPublic:
        items = [
            BatchItem(index=offset + i, job_id=f"j{offset + i}", state=s,
                      result=result_factory() if s is JobState.SUCCEEDED and with_result else None)
            for i, s in enumerate(states)
        ]  # fmt: skip
        counts = {JobState.SUCCEEDED: 2, JobState.QUEUED: 3}
        return BatchPublic(
            id="b", total=5, counts=counts, done=False, items=items, offset=offset, limit=2, created_at=0.0
        )

    fresh = tracker.update(page(0, [JobState.SUCCEEDED, JobState.RUNNING]))
    assert [i.index for i in fresh] == [0]
    assert tracker.worth_more_pages()  # counts say 2 finished, 1 reported
    fresh = tracker.update(page(2, [JobState.SUCCEEDED, JobState.QUEUED], with_result=False))
    assert fresh == [] and [i.index for i in tracker.missing_results()] == [2]
    assert tracker.update(page(0, [JobState.SUCCEEDED, JobState.RUNNING])) == []  # never twice
    assert tracker.pending_pages() == [0, 2, 4]
    assert not tracker.done


def test_sse_decoding() -> None:
    lines = [": keep-alive", "", "event: progress", 'data: {"a":', "data: 1}", "id: 7", "", "data: last"]
    events = list(iter_events(lines))
    assert [(e.event, e.data, e.id) for e in events] == [("progress", '{"a":\n1}', "7"), ("message", "last", "7")]


def _tracker_round(tracker: BatchTracker, states: list[JobState]) -> list[int]:
    """One polling round as the clients do it, against a batch whose items are in ``states``."""
    from manifoundation.contract import ErrorBody, JobPublic

    counts: dict[JobState, int] = {}
    for s in states:
        counts[s] = counts.get(s, 0) + 1
    fresh: list[int] = []
    for n, offset in enumerate(tracker.pending_pages()):
        if n > 0 and not tracker.worth_more_pages():
            break
        items = [
            BatchItem(index=i, job_id=f"j{i}", state=states[i],
                      error=ErrorBody(error="x", type="X") if states[i] is JobState.FAILED else None)
            for i in range(offset, min(offset + tracker.page_size, tracker.total))
        ]  # fmt: skip
        page = BatchPublic(id="b", total=tracker.total, counts=counts, done=False, items=items, offset=offset,
                           limit=tracker.page_size, created_at=0.0)  # fmt: skip
        fresh += [item.index for item in tracker.update(page)]
    for item in tracker.missing_results():  # succeeded, no result in the page: the client reads the job
        job = JobPublic(id=item.job_id, state=states[item.index], created_at=0.0)
        fresh.append(tracker.fill(item.index, job).index)
    return fresh


@settings(max_examples=60, deadline=None)
@given(st.integers(1, 40), st.integers(1, 12), st.randoms(use_true_random=False))
def test_batch_tracker_reports_every_item_exactly_once(total: int, page_size: int, rng: random.Random) -> None:
    """Items finish in any order (results never in the pages): each is reported once, none is lost."""
    states = [JobState.QUEUED] * total
    tracker = BatchTracker("b", total=total, page_size=page_size)
    reported: list[int] = []
    for _ in range(20):
        for i in rng.sample(range(total), k=rng.randint(0, total)):
            if not states[i].terminal:
                states[i] = rng.choice([JobState.RUNNING, JobState.SUCCEEDED, JobState.FAILED])
        reported += _tracker_round(tracker, states)
        assert len(reported) == len(set(reported))
        assert set(reported) == {i for i, s in enumerate(states) if s.terminal} or not tracker.worth_more_pages()
    states = [s if s.terminal else JobState.SUCCEEDED for s in states]
    reported += _tracker_round(tracker, states)
    assert tracker.done and sorted(reported) == list(range(total))


def test_a_client_given_no_url_reads_mani_url_then_the_local_default(monkeypatch: pytest.MonkeyPatch) -> None:
    import asyncio

    from manifoundation.sdk import AsyncClient, Client

    monkeypatch.setenv("MANI_URL", "http://grasps.example:9000/")
    with Client() as client:
        assert client.base_url == "http://grasps.example:9000"
    asynchronous = AsyncClient()
    assert asynchronous.base_url == "http://grasps.example:9000"
    asyncio.run(asynchronous.aclose())
    with Client("http://127.0.0.1:9001") as client:  # a URL given wins
        assert client.base_url == "http://127.0.0.1:9001"
    monkeypatch.setenv("MANI_URL", "")  # set but empty: as if unset
    assert BaseClient().base_url == "http://127.0.0.1:8000"
    monkeypatch.delenv("MANI_URL")
    assert BaseClient().base_url == "http://127.0.0.1:8000"
