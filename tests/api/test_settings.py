"""`Settings`: env prefix, comma-separated lists, fail-fast validation; the CLI's overrides."""

from __future__ import annotations

import argparse

import pytest
from pydantic import ValidationError

from manifoundation.server.api.cli import register, settings_from
from manifoundation.server.api.settings import Settings


def test_env(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("MANI_API_KEYS", "key-one-123, key-two-456")
    monkeypatch.setenv("MANI_PORT", "9001")
    monkeypatch.setenv("MANI_REDIS_URL", "redis://localhost:6379/3")
    monkeypatch.setenv("MANI_LOG_LEVEL", "debug")
    settings = Settings()
    assert settings.api_keys == ["key-one-123", "key-two-456"] and settings.auth_enabled
    assert settings.port == 9001 and settings.log_level == "DEBUG"
    queue = settings.queue_settings()
    assert queue.redis_url == "redis://localhost:6379/3" and queue.concurrency == 2  # one knob, one default


@pytest.mark.parametrize(
    "field, value",
    [("port", 70000), ("api_keys", "short"), ("sync_wait_max", 0), ("log_level", "LOUD")],
)
def test_bad_values_fail_fast(field: str, value: object) -> None:
    with pytest.raises(ValidationError):
        Settings(**{field: value})  # type: ignore[arg-type]


def test_cli_overrides_env(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("MANI_PORT", "9001")
    parser = argparse.ArgumentParser()
    register(parser.add_subparsers())
    args = parser.parse_args(["serve", "--port", "9100", "--workers", "3", "--redis", "redis://h:1/0"])
    settings = settings_from(args)
    queue = settings.queue_settings()
    assert (settings.port, queue.concurrency, queue.redis_url) == (9100, 3, "redis://h:1/0")
    assert args.func.__name__ == "serve"
