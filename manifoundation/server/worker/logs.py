"""Structured (JSON lines) logging with the job id, and the id of the HTTP request that submitted the job, on every
line logged while a job is being handled (follow one request from the service's logs to its worker)."""

from __future__ import annotations

import contextlib
import contextvars
import json
import logging
import sys
import time
from collections.abc import Iterator

_job_id: contextvars.ContextVar[str | None] = contextvars.ContextVar("mani_job_id", default=None)
_request_id: contextvars.ContextVar[str | None] = contextvars.ContextVar("mani_job_request_id", default=None)
_worker_id: str | None = None

_STANDARD = frozenset(vars(logging.LogRecord("", 0, "", 0, "", None, None))) | {"message", "asctime"}


class JsonFormatter(logging.Formatter):
    """One JSON object per line: ts, level, logger, msg, job_id, request_id, worker, and any ``extra=`` fields."""

    def format(self, record: logging.LogRecord) -> str:
        entry: dict[str, object] = {
            "ts": round(record.created, 6),
            "level": record.levelname,
            "logger": record.name,
            "msg": record.getMessage(),
        }
        job = getattr(record, "job_id", None) or _job_id.get()
        if job:
            entry["job_id"] = job
        request = getattr(record, "request_id", None) or _request_id.get()
        if request:
            entry["request_id"] = request
        if _worker_id:
            entry["worker"] = _worker_id
        for key, value in vars(record).items():
            if key not in _STANDARD and key not in entry:
                entry[key] = value if isinstance(value, str | int | float | bool | None) else repr(value)
        if record.exc_info:
            entry["exc"] = self.formatException(record.exc_info)
        return json.dumps(entry, default=str)


def setup_logging(level: str = "INFO", worker_id: str | None = None) -> None:
    """Send this process's logs to stderr as JSON lines (called once per worker process)."""
    global _worker_id
    _worker_id = worker_id
    handler = logging.StreamHandler(sys.stderr)
    handler.setFormatter(JsonFormatter())
    root = logging.getLogger()
    root.handlers[:] = [handler]
    root.setLevel(level.upper())


@contextlib.contextmanager
def job_context(job_id: str | None, request_id: str | None = None) -> Iterator[None]:
    """Every line logged inside carries ``job_id`` and, when the job has one, the ``request_id`` of the HTTP
    request that submitted it."""
    token = _job_id.set(job_id)
    request_token = _request_id.set(request_id)
    try:
        yield
    finally:
        _request_id.reset(request_token)
        _job_id.reset(token)


def now() -> float:
    """Unix time, seconds."""
    return time.time()
