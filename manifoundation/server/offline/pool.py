"""Rows through a worker loaded once per process: in this process, or a local spawn pool that survives a crash.

A *row* is one item of offline work as plain columns (``Row``: names → str / bytes / int / float), so the same rows
travel through a local pool and through Ray Data (`manifoundation.server.offline.ray_pool`) unchanged. A
`WorkerFactory` is a picklable zero-argument callable that loads the heavy state (a pipeline, a model, hands)
once and returns the `BatchFn` applied to every batch of rows that process gets.

Crashes: a worker process that dies (a segfault, the OOM killer) breaks a local pool. The rows no worker had begun
go back to a new pool; the rows that were running are retried one at a time in a pool of one process, so a crash
names its row, up to ``max_attempts`` crashes each. A row given up is *not* yielded: the caller records each
missing row (see `manifoundation.server.offline.batch`).
"""

from __future__ import annotations

import multiprocessing as mp
import os
import tempfile
from collections import Counter
from collections.abc import Callable, Generator, Iterator
from concurrent.futures import ProcessPoolExecutor, as_completed
from concurrent.futures.process import BrokenProcessPool
from pathlib import Path
from typing import Protocol

Value = str | bytes | int | float
Row = dict[str, Value]
"""One item of offline work (or its answer) as named plain columns; every row has a unique ``"id"`` (str)."""


class BatchFn(Protocol):
    """The per-process worker: answer rows → one answer row each (any order; ``"id"`` kept)."""

    def __call__(self, rows: list[Row]) -> list[Row]: ...


WorkerFactory = Callable[[], BatchFn]
"""Loads a worker once per process (or Ray actor); must be picklable (a module-level class instance)."""

_WORKER: BatchFn | None = None
_MARK: Path | None = None  # where this pool process marks the rows it is running


def chunks(rows: list[Row], size: int) -> list[list[Row]]:
    """``rows`` in consecutive batches of at most ``size``."""
    size = max(1, size)
    return [rows[i : i + size] for i in range(0, len(rows), size)]


def run_local(rows: list[Row], factory: WorkerFactory, *, workers: int = 1, batch_size: int = 8,
              max_attempts: int = 3) -> Iterator[list[Row]]:  # fmt: skip
    """Answer rows batch by batch, as they finish: in this process when ``workers`` ≤ 1, else in ``workers``
    spawned processes each loading ``factory`` once. Rows whose process died ``max_attempts`` times are left out."""
    if workers <= 1:
        fn = factory()
        for batch in chunks(rows, batch_size):
            yield fn(batch)
        return
    yield from _pooled(rows, factory, workers, batch_size, max_attempts)


def _pooled(rows: list[Row], factory: WorkerFactory, workers: int, batch_size: int,
            max_attempts: int) -> Iterator[list[Row]]:  # fmt: skip
    pending = rows
    while pending:
        lost, started = yield from _until_broken(pending, factory, workers, batch_size)
        pending = [row for row in lost if str(row["id"]) not in started]  # never began: back to the pool
        yield from _isolated([row for row in lost if str(row["id"]) in started], factory, max_attempts)


def _until_broken(rows: list[Row], factory: WorkerFactory, workers: int,
                  batch_size: int) -> Generator[list[Row], None, tuple[list[Row], set[str]]]:  # fmt: skip
    """Answer ``rows`` in a pool until it breaks; returns the rows left without an answer and the ids of the rows
    a worker had begun (each worker marks its batch in a file of its own before running it)."""
    with tempfile.TemporaryDirectory(prefix="mani-pool-") as marks:
        pool = ProcessPoolExecutor(workers, mp_context=mp.get_context("spawn"), initializer=_load,
                                   initargs=(factory, marks))  # fmt: skip
        with pool:
            futures = {pool.submit(_answer, batch): batch for batch in chunks(rows, batch_size)}
            try:
                for future in as_completed(futures):
                    yield future.result()
                    del futures[future]
            except BrokenProcessPool:
                for future in [f for f in futures if f.done() and f.exception() is None]:
                    yield future.result()  # answered before the break
                    del futures[future]
        started = {line for mark in Path(marks).iterdir() for line in mark.read_text().splitlines()}
    return [row for batch in futures.values() for row in batch], started


def _isolated(suspects: list[Row], factory: WorkerFactory, max_attempts: int) -> Iterator[list[Row]]:
    """Rows that were running when a worker died, one at a time in a pool of one: a crash names its row exactly.
    A row given up (its ``max_attempts``-th crash, the first counted) is left out."""
    crashes: Counter[str] = Counter({str(row["id"]): 1 for row in suspects})
    queue = list(suspects)
    while queue:
        with ProcessPoolExecutor(1, mp_context=mp.get_context("spawn"), initializer=_load,
                                 initargs=(factory, None)) as pool:  # fmt: skip
            try:
                while queue:
                    answer = pool.submit(_answer, queue[:1]).result()
                    queue.pop(0)
                    yield answer
            except BrokenProcessPool:
                crashes[str(queue[0]["id"])] += 1
                if crashes[str(queue[0]["id"])] >= max_attempts:
                    queue.pop(0)


def _load(factory: WorkerFactory, marks: str | None) -> None:
    global _WORKER, _MARK
    _WORKER = factory()
    _MARK = Path(marks) / str(os.getpid()) if marks else None


def _answer(rows: list[Row]) -> list[Row]:
    assert _WORKER is not None, "the pool's initializer did not run"
    if _MARK is not None:
        _MARK.write_text("\n".join(str(row["id"]) for row in rows))
    return _WORKER(rows)
