"""Rows through a worker loaded once per process: in this process, or a local spawn pool that survives a crash.

A *row* is one item of offline work as plain columns (``Row``: names → str / bytes / int / float), so the same rows
travel through a local pool and through Ray Data (`manifoundation.server.offline.ray_pool`) unchanged. A
`WorkerFactory` is a picklable zero-argument callable that loads the heavy state (a pipeline, a model, hands)
once and returns the `BatchFn` applied to every batch of rows that process gets.

Crashes: a worker process that dies (a segfault, the OOM killer) breaks a local pool; the pool is started again
and the rows that were in flight are retried one by one, up to ``max_attempts`` times each. Rows still without an
answer after that are *not* yielded: the caller records each missing row (see `manifoundation.server.offline.batch`).
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Callable, Iterator
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
    import multiprocessing as mp
    from concurrent.futures import Future, ProcessPoolExecutor, as_completed
    from concurrent.futures.process import BrokenProcessPool

    attempts: Counter[str] = Counter()
    todo = chunks(rows, batch_size)
    while todo:
        lost: list[Row] = []
        pool = ProcessPoolExecutor(workers, mp_context=mp.get_context("spawn"), initializer=_load, initargs=(factory,))
        with pool:
            futures: dict[Future[list[Row]], list[Row]] = {pool.submit(_answer, batch): batch for batch in todo}
            try:
                for future in as_completed(futures):
                    yield future.result()
                    del futures[future]
            except BrokenProcessPool:
                lost = [row for batch in futures.values() for row in batch]
        attempts.update(str(row["id"]) for row in lost)
        todo = [[row] for row in lost if attempts[str(row["id"])] < max_attempts]  # one by one: find the culprit


def _load(factory: WorkerFactory) -> None:
    global _WORKER
    _WORKER = factory()


def _answer(rows: list[Row]) -> list[Row]:
    assert _WORKER is not None, "the pool's initializer did not run"
    return _WORKER(rows)
