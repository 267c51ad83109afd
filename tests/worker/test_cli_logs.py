"""`mani worker` argument handling, settings from the environment, and JSON log lines carrying the job id and the
id of the HTTP request that submitted it."""

from __future__ import annotations

import io
import json
import logging
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

import pytest

from manifoundation.cli.main import main
from manifoundation.contract import SynthesisResult
from manifoundation.server.queue import create_queue, queue_settings
from manifoundation.server.queue.embedded import EmbeddedQueue
from manifoundation.server.queue.redis import RedisQueue
from manifoundation.server.worker.logs import JsonFormatter, job_context
from manifoundation.server.worker.pipeline import CancelFn, JobInput, Outcome, ProgressFn
from manifoundation.server.worker.runner import run_batch
from manifoundation.server.worker.settings import QueueSettings
from research.staged_pipeline import StagedPipeline

from .helpers import small_request


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


@contextmanager
def json_log_lines(logger: logging.Logger) -> Iterator[list[dict[str, Any]]]:
    """Capture ``logger``'s INFO+ lines through the worker's JsonFormatter; the list is filled, parsed, on exit.

    The formatter runs at emit time, so each line sees the job context active when it was logged.
    """
    stream = io.StringIO()
    handler = logging.StreamHandler(stream)
    handler.setFormatter(JsonFormatter())
    logger.addHandler(handler)
    logger.setLevel(logging.INFO)
    lines: list[dict[str, Any]] = []
    try:
        yield lines
    finally:
        logger.removeHandler(handler)
        lines.extend(json.loads(line) for line in stream.getvalue().splitlines())


def test_log_lines_are_json_with_the_job_id() -> None:
    logger = logging.getLogger("workers.test")
    with json_log_lines(logger) as lines:
        with job_context("abc123"):
            logger.info("job started", extra={"delivery": 2})
        logger.info("idle")
    first, second = lines
    assert first["job_id"] == "abc123" and first["msg"] == "job started" and first["delivery"] == 2
    assert "job_id" not in second and second["level"] == "INFO"


def test_log_lines_carry_the_request_id_next_to_the_job_id() -> None:
    logger = logging.getLogger("workers.test")
    with json_log_lines(logger) as lines:
        with job_context("job-1", "abc-123"):
            logger.info("job started")
        with job_context("job-2"):  # a job submitted without one (an older service, a script)
            logger.info("job started")
        logger.info("idle")
    first, second, third = lines
    assert (first["job_id"], first["request_id"]) == ("job-1", "abc-123")
    assert second["job_id"] == "job-2" and "request_id" not in second
    assert "job_id" not in third and "request_id" not in third


class _LoggingPipeline(StagedPipeline):
    """Logs from inside `run`, the way a real pipeline's own code would."""

    def run(self, jobs: list[JobInput], progress: ProgressFn, should_cancel: CancelFn) -> list[Outcome]:
        logging.getLogger("workers.test.pipeline").info("running %d", len(jobs))
        return super().run(jobs, progress, should_cancel)


def test_lines_logged_while_a_job_runs_carry_its_ids() -> None:
    one = JobInput(id="job-1", request=small_request(1), request_id="abc-123")
    other = JobInput(id="job-2", request=small_request(2), request_id="abc-456")
    with json_log_lines(logging.getLogger("workers.test.pipeline")) as lines:
        outcomes = run_batch(_LoggingPipeline(), [one], lambda *_: None, lambda _: False)
        assert isinstance(outcomes["job-1"], SynthesisResult)
        run_batch(_LoggingPipeline(), [one, other], lambda *_: None, lambda _: False)
    single, batch = lines
    assert (single["job_id"], single["request_id"]) == ("job-1", "abc-123")
    assert "job_id" not in batch and "request_id" not in batch  # a batch of several is nobody's in particular
