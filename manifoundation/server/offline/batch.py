"""A batch of request files through the worker core, locally or on Ray, resumable, every request accounted for.

``run_batch(requests_dir, out_dir, worker, ...)``: list the items (`items.list_items`), skip the finished ones
(`store.ResultStore.finished`), then a `WINDOW` of requests at a time: read them, record the unreadable ones at
once (``BadRequest``), run the rest through a local pool (`pool.run_local`) or a Ray Data actor pool
(`ray_pool.run_ray`, when ``ray_address`` is given) and write each answer as it comes. A request that got no
answer (its worker died on every retry, or the run itself stopped with an error) is recorded as ``WorkerLost``,
so nothing is dropped; a rerun runs it again.
"""

from __future__ import annotations

import json
import logging
import time
from collections.abc import Iterator
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import TYPE_CHECKING, NoReturn

from manifoundation.contract import ErrorBody, ErrorType, JobState
from manifoundation.server.offline.items import Item, list_items, load
from manifoundation.server.offline.pool import Row, WorkerFactory, run_local
from manifoundation.server.offline.store import ResultStore

WINDOW = 10_000
"""Requests read into memory (and handed to the pool) at a time: ~130 MB of 256-point requests, ~1 GB of 2048-point
ones (points and normals as float64). Each window starts the pool's workers again (seconds)."""

if TYPE_CHECKING:
    from tqdm import tqdm

log = logging.getLogger("manifoundation.server.offline.batch")


@dataclass
class BatchSummary:
    """One run's figures (``summary.json``): items found, skipped as finished, run, and of those answered; the
    directory's result counts (``succeeded`` and one per error type) after the run; wall seconds and items/s."""

    found: int
    skipped: int
    ran: int
    answered: int
    counts: dict[str, int]
    seconds: float
    items_per_s: float
    backend: str


def run_batch(requests_dir: Path, out_dir: Path, worker: WorkerFactory, *, ray_address: str | None = None,
              workers: int = 1, batch_size: int = 8, retry_failed: bool = False, window: int = WINDOW,
              progress: bool = True) -> BatchSummary:  # fmt: skip
    """Run every unfinished request of ``requests_dir`` and record its outcome in ``out_dir`` (module doc)."""
    from tqdm import tqdm

    store = ResultStore(out_dir)
    refs = list_items(requests_dir)
    finished = store.finished(retry_failed)
    todo = [ref for ref in refs if ref.id not in finished]
    t0 = time.perf_counter()
    bar = tqdm(total=len(refs), initial=len(refs) - len(todo), unit="req", disable=not progress, smoothing=0.1)
    answered: set[str] = set()
    connected = False
    try:
        if ray_address is not None and todo:
            from manifoundation.server.offline.ray_pool import connect

            connected = connect(ray_address)  # once for every window
        for start in range(0, len(todo), max(1, window)):
            _run_window(store, [load(ref) for ref in todo[start : start + window]], worker, ray_address, workers,
                        batch_size, answered, bar)  # fmt: skip
    finally:  # an interrupted run (Ctrl-C) records nothing more: the rerun runs what has no file
        bar.close()
        if connected:
            from manifoundation.server.offline.ray_pool import disconnect

            disconnect()
        seconds = time.perf_counter() - t0
        summary = BatchSummary(
            found=len(refs), skipped=len(refs) - len(todo), ran=len(todo), answered=len(answered),
            counts=store.counts(), seconds=seconds, items_per_s=len(answered) / seconds if seconds else 0.0,
            backend=f"ray {ray_address}" if ray_address else f"local x{workers}",
        )  # fmt: skip
        store.write_summary(asdict(summary))
    return summary


def _run_window(store: ResultStore, items: list[Item], worker: WorkerFactory, ray_address: str | None, workers: int,
                batch_size: int, answered: set[str], bar: tqdm[NoReturn]) -> None:  # fmt: skip
    """Record the window's unreadable items, run the others and record every outcome (the lost ones included)."""
    for item in items:
        if item.error is not None:
            store.write_error(item.id, item.error, JobState.FAILED.value, {})
            bar.update(1)
    rows: list[Row] = [{"id": item.id, "request": item.request} for item in items if item.error is None]
    try:
        for batch in _answers(rows, worker, ray_address, workers, batch_size):
            for row in batch:
                _record(store, row)
                answered.add(str(row["id"]))
            bar.update(len(batch))
    except Exception as exc:  # the pool or the cluster failed: what did not finish is recorded, then re-raised
        _record_lost(store, rows, answered, f"the run stopped: {exc.__class__.__name__}: {exc}")
        raise
    _record_lost(store, rows, answered, "its worker was lost on every try")


def _answers(rows: list[Row], worker: WorkerFactory, ray_address: str | None, workers: int,
             batch_size: int) -> Iterator[list[Row]]:  # fmt: skip
    if ray_address is None:
        return run_local(rows, worker, workers=workers, batch_size=batch_size)
    from manifoundation.server.offline.ray_pool import run_ray

    return run_ray(rows, worker, address=ray_address, workers=workers, batch_size=batch_size)


def _record(store: ResultStore, row: Row) -> None:
    item_id, result, error = str(row["id"]), row["result"], str(row["error"])
    timings: dict[str, float] = json.loads(str(row["timings"]))
    if isinstance(result, bytes) and result and row["state"] == JobState.SUCCEEDED.value:
        store.write_result(item_id, result)
    else:
        store.write_error(item_id, ErrorBody.model_validate_json(error), str(row["state"]), timings)


def _record_lost(store: ResultStore, rows: list[Row], answered: set[str], why: str) -> None:
    for item_id in (str(row["id"]) for row in rows if str(row["id"]) not in answered):
        log.warning("request %s got no answer: %s", item_id, why)
        store.write_error(item_id, ErrorBody.of(ErrorType.WORKER_LOST, f"no answer: {why}"), JobState.FAILED.value, {})
