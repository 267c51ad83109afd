"""The batch command's worker: the service's `WorkerCore` over rows, loaded once per process or Ray actor.

In: rows ``{"id": str, "request": bytes}`` (msgpack of a `SynthesisRequest`). Out: rows ``{"id", "state"
(a `JobState` value), "result": bytes (msgpack of the `SynthesisResult`, b"" on failure), "error": str (JSON of
the `ErrorBody`, "" on success), "timings": str (JSON)}``. A batch of rows is one micro-batch of the core, exactly
as a queue delivery is: decoded and validated once, run, a failure isolated to its own request, encoded once.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field

from manifoundation.contract import JobProgress
from manifoundation.server.offline.pool import BatchFn, Row
from manifoundation.server.worker.core import Finished, RawJob, WorkerCore

OptionValue = str | int | float | bool | None | list[str]


@dataclass(frozen=True)
class SynthesisWorker:
    """A picklable `WorkerFactory`: which pipeline (``"module:attr"``), with which keyword options and weights."""

    pipeline: str = "manifoundation.server.worker.models_pipeline:ModelsPipeline"
    options: dict[str, OptionValue] = field(default_factory=dict)
    weights_dir: str | None = None

    def __call__(self) -> BatchFn:
        from manifoundation.server.worker.pipeline import load_pipeline

        return _CoreBatch(WorkerCore(load_pipeline(self.pipeline, dict(self.options), self.weights_dir)))


class _CoreBatch:
    def __init__(self, core: WorkerCore) -> None:
        self.core = core

    def __call__(self, rows: list[Row]) -> list[Row]:
        raw = [RawJob(id=str(row["id"]), request=_bytes(row["request"])) for row in rows]
        return [answer_row(f) for f in self.core.run(raw, _no_progress, _never)]


def answer_row(finished: Finished) -> Row:
    """One `Finished` outcome as an answer row (see module doc)."""
    error = finished.error.model_dump_json(exclude_none=True) if finished.error is not None else ""
    return {"id": finished.id, "state": finished.state.value, "result": finished.result or b"", "error": error,
            "timings": json.dumps(finished.timings)}  # fmt: skip


def _bytes(value: object) -> bytes:
    if not isinstance(value, bytes):
        raise TypeError(f"a request row holds bytes, not {type(value).__name__}")
    return value


def _no_progress(job_id: str, progress: JobProgress) -> None:
    """Offline work shows progress per item finished, not per stage."""


def _never(job_id: str) -> bool:
    return False
