"""Fuzz the API from its own OpenAPI schema (schemathesis): whatever arrives, never a 5xx, and every answer
matches its documented schema; against the in-memory fake queue and the real embedded queue (a worker process
running the staged pipeline) and, in the `slow` run, the Redis queue with a `mani worker`. Bounded: 10 cases
per operation and backend by default (a few hundred in all); the `slow` run does ``MANI_FUZZ_EXAMPLES`` (200) per
operation and prints how many cases each backend answered."""

from __future__ import annotations

import json
import os
import sys
import time
from collections import Counter
from collections.abc import Iterator
from typing import Any

import httpx
import pytest
import schemathesis
from hypothesis import HealthCheck, settings
from schemathesis.checks import content_type_conformance, not_a_server_error, response_schema_conformance
from schemathesis.config import SchemathesisConfig

from manifoundation.contract.codec import pack
from manifoundation.server.api.app import create_app
from manifoundation.server.api.settings import Settings
from manifoundation.server.queue import create_queue

from .fakes import FakeQueue
from .server import serving
from .workers import start_queue_and_workers

KEY = "fuzz-test-key-1"
STAGED = "research.staged_pipeline:StagedPipeline"


@schemathesis.serializer("application/msgpack")
def _msgpack(ctx: Any, value: Any) -> bytes:
    try:
        return pack(value)
    except (TypeError, ValueError, OverflowError):
        return json.dumps(value).encode()  # e.g. an int beyond 64 bits: the server must answer 400, not 500


def _app(queue: Any = None) -> Any:
    settings = Settings(api_keys=[KEY], rate_limit_per_s=0, sync_wait_max=1, auth_failures_per_s=0)
    return create_app(settings, queue=queue or FakeQueue())


# The coverage phase enumerates every boundary of every field (thousands of cases for the request schema);
# examples + fuzzing with `max_examples` keep the default run bounded.
CONFIG = SchemathesisConfig.from_dict({"phases": {"coverage": {"enabled": False}, "stateful": {"enabled": False}}})
schema = schemathesis.openapi.from_dict(_app().openapi(), config=CONFIG)


LONG_EXAMPLES = int(os.environ.get("MANI_FUZZ_EXAMPLES", "200"))
CASES: Counter[str] = Counter()  # answered cases per base URL


@pytest.fixture(scope="module", params=["fake", "embedded", pytest.param("redis", marks=pytest.mark.slow)])
def base_url(request: pytest.FixtureRequest) -> Iterator[str]:
    if request.param == "redis":  # a `mani worker` behind the Redis queue, keys under a prefix of this module's
        with start_queue_and_workers(request, max_queue=1000) as queue, serving(_app(queue)) as base:
            _until_ready(base)
            yield base
            _report("redis", base)
        return
    queue = None
    if request.param == "embedded":
        queue = create_queue(None, redis_url=None, concurrency=1, pipeline=STAGED, max_queue=1000, log_level="ERROR")
    with serving(_app(queue)) as base:
        yield base
        _report(request.param, base)


def _until_ready(base: str, timeout: float = 60) -> None:
    """Wait for /readyz 200 (the worker has sent its first heartbeat)."""
    end = time.monotonic() + timeout
    while httpx.get(f"{base}/readyz").status_code != 200:
        if time.monotonic() > end:
            raise AssertionError("the Redis-backed service did not become ready")
        time.sleep(0.2)


def _report(backend: str, base: str) -> None:
    print(f"\nfuzz: {CASES[base]} cases answered by the {backend} backend", file=sys.__stderr__, flush=True)


def _check(case: Any, base_url: str) -> None:
    CASES[base_url] += 1
    case.call_and_validate(
        base_url=base_url,
        headers={"Authorization": f"Bearer {KEY}"},
        checks=[not_a_server_error, response_schema_conformance, content_type_conformance],
        timeout=30,
    )


@schema.parametrize()
@settings(max_examples=10, deadline=None, suppress_health_check=list(HealthCheck), derandomize=True)
def test_no_server_errors(case: Any, base_url: str) -> None:
    _check(case, base_url)


@pytest.mark.slow
@schema.parametrize()
@settings(max_examples=LONG_EXAMPLES, deadline=None, suppress_health_check=list(HealthCheck))
def test_no_server_errors_long(case: Any, base_url: str) -> None:
    _check(case, base_url)
