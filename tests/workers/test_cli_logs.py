"""`mani worker` argument handling, settings from the environment, and JSON log lines carrying the job id."""

from __future__ import annotations

import io
import json
import logging

import pytest

from clients.cli.main import main
from workers.logs import JsonFormatter, job_context
from workers.queue import create_queue, queue_settings
from workers.queue.embedded import EmbeddedQueue
from workers.queue.redis import RedisQueue
from workers.settings import QueueSettings


def test_worker_needs_redis(monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]) -> None:
    monkeypatch.delenv("MANI_REDIS_URL", raising=False)
    assert main(["worker", "--concurrency", "1"]) == 2
    assert "MANI_REDIS_URL" in capsys.readouterr().err
    assert main(["worker", "--redis", "redis://x", "--batch-size", "0"]) == 2  # fails fast on bad settings


def test_settings_from_env_and_factory(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("MANI_BATCH_SIZE", "8")
    monkeypatch.setenv("MANI_PIPELINE_OPTIONS", '{"stage_seconds": 0.5}')
    monkeypatch.delenv("MANI_REDIS_URL", raising=False)
    settings = QueueSettings()
    assert settings.batch_size == 8 and settings.pipeline_options == {"stage_seconds": 0.5}
    assert isinstance(create_queue(), EmbeddedQueue)
    assert isinstance(create_queue("redis://localhost:6379/0"), RedisQueue)

    class ServiceSettings:  # another settings object sharing some field names
        redis_url = None
        concurrency = 3
        port = 8000

    assert queue_settings(ServiceSettings(), max_queue=5).model_dump(include={"concurrency", "max_queue"}) == {
        "concurrency": 3,
        "max_queue": 5,
    }


def test_log_lines_are_json_with_the_job_id() -> None:
    stream = io.StringIO()
    handler = logging.StreamHandler(stream)
    handler.setFormatter(JsonFormatter())
    logger = logging.getLogger("workers.test")
    logger.addHandler(handler)
    logger.setLevel(logging.INFO)
    try:
        with job_context("abc123"):
            logger.info("job started", extra={"delivery": 2})
        logger.info("idle")
    finally:
        logger.removeHandler(handler)
    first, second = (json.loads(line) for line in stream.getvalue().splitlines())
    assert first["job_id"] == "abc123" and first["msg"] == "job started" and first["delivery"] == 2
    assert "job_id" not in second and second["level"] == "INFO"
