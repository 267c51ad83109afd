"""`GET /mcp` event streams are bounded (reliability issue 62, item 7): each key holds at most
``MANI_MCP_MAX_STREAMS`` at once (429 beyond, another key unaffected), and each stream ends after
``MANI_MCP_STREAM_MAX_S`` — before, 600 streams from one key stayed open for good, one file descriptor each. A real
uvicorn server and the MCP SDK's real app; the queue is a fake (no job is submitted)."""

from __future__ import annotations

import threading
import time
from collections.abc import Iterator

import httpx
import pytest

from manifoundation.server.api.app import create_app
from manifoundation.server.api.settings import Settings

from ..fakes import FakeQueue
from ..server import serving

KEYS = ("stream-key-0001", "stream-key-0002")
STREAM = {"Accept": "text/event-stream"}


@pytest.fixture(scope="module")
def base() -> Iterator[str]:
    settings = Settings(api_keys=list(KEYS), mcp_stream_max_s=2.0, mcp_max_streams=2, rate_limit_per_s=0)
    with serving(create_app(settings, queue=FakeQueue())) as url:  # type: ignore[arg-type]
        yield url


def _open(base: str, key: str, seconds: list[float], codes: list[int]) -> None:
    """Hold one event stream until the server ends it; record its status and how long it stayed open."""
    started = time.monotonic()
    with httpx.stream("GET", f"{base}/mcp", headers={**STREAM, "Authorization": f"Bearer {key}"}, timeout=30) as r:
        codes.append(r.status_code)
        for _ in r.iter_bytes():
            pass
    seconds.append(time.monotonic() - started)


def test_a_stream_ends_after_its_longest_life(base: str) -> None:
    seconds: list[float] = []
    codes: list[int] = []
    _open(base, KEYS[0], seconds, codes)
    assert codes == [200]
    assert 1.5 < seconds[0] < 10, seconds  # ended by the server at ~2 s, not held open


def test_a_key_holds_at_most_its_streams_and_another_key_is_not_affected(base: str) -> None:
    seconds: list[float] = []
    codes: list[int] = []
    held = [threading.Thread(target=_open, args=(base, KEYS[0], seconds, codes)) for _ in range(2)]
    for thread in held:
        thread.start()
    deadline = time.monotonic() + 5
    while len(codes) < 2 and time.monotonic() < deadline:
        time.sleep(0.02)
    assert codes == [200, 200]
    third = httpx.get(f"{base}/mcp", headers={**STREAM, "Authorization": f"Bearer {KEYS[0]}"}, timeout=10)
    assert third.status_code == 429 and "MANI_MCP_MAX_STREAMS" in third.json()["error"]
    assert int(third.headers["Retry-After"]) >= 1
    other: list[int] = []
    _open(base, KEYS[1], [], other)
    assert other == [200]
    for thread in held:
        thread.join(timeout=15)
    again: list[int] = []
    _open(base, KEYS[0], [], again)  # the ended streams were counted off
    assert again == [200]


def test_a_burst_of_streams_from_one_key_gets_its_limit_and_no_more(base: str) -> None:
    """The count is taken with the check: 12 streams opened at once got 12 × 200 before (every check passed before
    any stream was counted)."""
    codes: list[int] = []
    burst = [threading.Thread(target=_open, args=(base, KEYS[0], [], codes)) for _ in range(12)]
    for thread in burst:
        thread.start()
    for thread in burst:
        thread.join(timeout=20)
    assert sorted(codes) == [200] * 2 + [429] * 10, codes


def test_a_body_declared_over_the_mcp_limit_is_refused_before_it_is_read(base: str) -> None:
    """MANI_MCP_MAX_BODY_BYTES (the HTTP body limit by default): a body declared larger is refused with a 413 that
    names the limit and says where larger clouds go, before the body is read."""
    limit = Settings().mcp_max_body_bytes
    headers = {"Authorization": f"Bearer {KEYS[0]}", "Content-Type": "application/json",
               "Accept": "application/json, text/event-stream"}  # fmt: skip
    started = time.monotonic()
    answer = httpx.post(f"{base}/mcp", content=b" " * (limit + 1), headers=headers, timeout=30)
    assert answer.status_code == 413 and "MANI_MCP_MAX_BODY_BYTES" in answer.json()["error"]
    assert "/v1" in answer.json()["error"] and time.monotonic() - started < 5
