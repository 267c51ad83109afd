"""The batch command's results: one file per request in the output directory, written atomically.

``ID.msgpack`` holds a succeeded request's `SynthesisResult`, the very bytes the service's queue stores (read it
with ``SynthesisResult.model_validate(unpack(data))``); ``ID.error.json`` holds a finished-with-error request's
``{"error", "type", "detail", "state", "timings"}`` (``type`` from `manifoundation.contract.errors.ErrorType`).
A request is *finished* when either file exists, so a rerun skips it; an error of a transient type (`RETRIED`:
the worker was lost) is not finished, and the rerun runs that request again. ``summary.json`` counts one run.

Why a file per request, not Parquet shards: resuming is exact (a file exists or not; there is no half-written
shard to repair after a kill), the result bytes are the service's own, so every tool that reads a job's result
reads these, and the results of 10^5 requests are 10^5 files, which any file system and ``ls``/``rsync`` handle.
"""

from __future__ import annotations

import json
import os
from collections import Counter
from pathlib import Path

from manifoundation.contract import ErrorBody, ErrorType

RESULT, ERROR = ".msgpack", ".error.json"
RETRIED = frozenset({ErrorType.WORKER_LOST.value})
"""Error types a rerun retries (the request itself may be fine)."""


class ResultStore:
    """The output directory of a batch (see module doc)."""

    def __init__(self, directory: Path) -> None:
        self.directory = directory
        directory.mkdir(parents=True, exist_ok=True)

    def finished(self, retry_failed: bool = False) -> set[str]:
        """Ids of the requests a rerun skips: succeeded, or failed with a final error (none with
        ``retry_failed``)."""
        done = {p.name.removesuffix(RESULT) for p in self.directory.glob("*" + RESULT)}
        if retry_failed:
            return done
        for path in self.directory.glob("*" + ERROR):
            if json.loads(path.read_text()).get("type") not in RETRIED:
                done.add(path.name.removesuffix(ERROR))
        return done

    def write_result(self, item_id: str, result: bytes) -> None:
        """Record a success (msgpack of a `SynthesisResult`); an older error file of the item goes."""
        self._replace(self.directory / (item_id + RESULT), result)
        (self.directory / (item_id + ERROR)).unlink(missing_ok=True)

    def write_error(self, item_id: str, error: ErrorBody, state: str, timings: dict[str, float]) -> None:
        """Record a failure with its contract error, the job state it ends in and its timings."""
        body = error.model_dump(mode="json", exclude_none=True) | {"state": state, "timings": timings}
        self._replace(self.directory / (item_id + ERROR), json.dumps(body, indent=1).encode())

    def counts(self) -> dict[str, int]:
        """Results in the directory: ``succeeded`` and one count per error type."""
        counts: Counter[str] = Counter(succeeded=len(list(self.directory.glob("*" + RESULT))))
        counts.update(json.loads(p.read_text())["type"] for p in self.directory.glob("*" + ERROR))
        return dict(counts)

    def write_summary(self, summary: dict[str, object]) -> None:
        """``summary.json``: the last run's figures and the directory's counts."""
        self._replace(self.directory / "summary.json", json.dumps(summary, indent=1).encode())

    @staticmethod
    def _replace(path: Path, data: bytes) -> None:
        tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
        tmp.write_bytes(data)
        os.replace(tmp, path)
