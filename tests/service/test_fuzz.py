"""Fuzz the API from its own OpenAPI schema (schemathesis): whatever arrives, never a 5xx, and every answer
matches its documented schema. Bounded: ~15 cases per operation by default (a few hundred in all); the
`slow` run does 200 per operation."""

from __future__ import annotations

import json
from collections.abc import Iterator
from typing import Any

import pytest
import schemathesis
from hypothesis import HealthCheck, settings
from schemathesis.checks import content_type_conformance, not_a_server_error, response_schema_conformance
from schemathesis.config import SchemathesisConfig

from clients.codec import pack
from service.app import create_app
from service.settings import Settings

from .fakes import FakeQueue
from .server import serving

KEY = "fuzz-test-key-1"


@schemathesis.serializer("application/msgpack")
def _msgpack(ctx: Any, value: Any) -> bytes:
    try:
        return pack(value)
    except (TypeError, ValueError, OverflowError):
        return json.dumps(value).encode()  # e.g. an int beyond 64 bits: the server must answer 400, not 500


def _app() -> Any:
    return create_app(Settings(api_keys=[KEY], rate_limit_per_s=0, sync_wait_max=1), queue=FakeQueue())


# The coverage phase enumerates every boundary of every field (thousands of cases for the request schema);
# examples + fuzzing with `max_examples` keep the default run bounded.
CONFIG = SchemathesisConfig.from_dict({"phases": {"coverage": {"enabled": False}, "stateful": {"enabled": False}}})
schema = schemathesis.openapi.from_dict(_app().openapi(), config=CONFIG)


@pytest.fixture(scope="module")
def base_url() -> Iterator[str]:
    with serving(_app()) as base:
        yield base


def _check(case: Any, base_url: str) -> None:
    case.call_and_validate(
        base_url=base_url,
        headers={"Authorization": f"Bearer {KEY}"},
        checks=[not_a_server_error, response_schema_conformance, content_type_conformance],
        timeout=30,
    )


@schema.parametrize()
@settings(max_examples=15, deadline=None, suppress_health_check=list(HealthCheck), derandomize=True)
def test_no_server_errors(case: Any, base_url: str) -> None:
    _check(case, base_url)


@pytest.mark.slow
@schema.parametrize()
@settings(max_examples=200, deadline=None, suppress_health_check=list(HealthCheck))
def test_no_server_errors_long(case: Any, base_url: str) -> None:
    _check(case, base_url)
