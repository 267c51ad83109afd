"""The same rows through a Ray Data actor pool: one actor per worker, each loading its `WorkerFactory` once.

``ray.data.from_items(rows)`` (a block a batch) → ``map_batches(_Actor, compute=ActorPoolStrategy(size=workers))``
→ streamed back to the caller with ``iter_batches`` (backpressure: the driver writes answers as they come, the
object store holds only what is in flight). Ray Data restarts a dead actor and retries its batch
(`MAX_TASK_RETRIES` times, then the block is given up); the rows of a block given up run again one per block, and
a row given up again is left out of the answers like a local pool's lost rows, so the caller records what is
missing. Ray is imported here only inside the functions: it is an optional extra.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Iterator
from typing import TYPE_CHECKING

from manifoundation.server.offline.pool import Row, Value, WorkerFactory

if TYPE_CHECKING:
    import numpy as np

MAX_TASK_RETRIES = 3
"""A batch whose actor died this many more times is given up (its rows recorded as lost by the caller)."""


class _Actor:
    """Ray Data's callable class: the worker loaded once per actor, numpy batches in and out."""

    def __init__(self, factory: WorkerFactory) -> None:
        self.fn = factory()

    def __call__(self, batch: dict[str, np.ndarray]) -> dict[str, list[Value]]:
        answers = self.fn(rows_of(batch))
        return {name: [row[name] for row in answers] for name in (answers[0] if answers else {})}


def rows_of(batch: dict[str, np.ndarray]) -> list[Row]:
    """A numpy batch of columns (each ``(B,)``) → ``B`` rows of plain Python values."""
    names = list(batch)
    count = len(batch[names[0]]) if names else 0
    return [{name: _plain(batch[name][i]) for name in names} for i in range(count)]


def _plain(value: object) -> Value:
    item = value.item() if hasattr(value, "item") and not isinstance(value, bytes | str) else value
    if not isinstance(item, str | bytes | int | float):
        raise TypeError(f"a row value must be str, bytes, int or float, not {type(item).__name__}")
    return item


def connect(address: str) -> bool:
    """Join the cluster at ``address`` (``ray://host:10001``, ``host:6379``, ``auto``), or start a local one bound
    to 127.0.0.1 for ``local``; returns whether this call started the connection (the caller then shuts it)."""
    import ray

    if ray.is_initialized():
        return False
    if address == "local":  # a cluster of this machine alone, reachable from it alone
        ray.init(_node_ip_address="127.0.0.1", include_dashboard=False, log_to_driver=False)
    else:
        ray.init(address=address, log_to_driver=False)
    return True


def disconnect() -> None:
    """Leave the cluster (`connect` returned True)."""
    import ray

    ray.shutdown()


def run_ray(rows: list[Row], factory: WorkerFactory, *, address: str, workers: int = 1, batch_size: int = 8,
            cpus_per_worker: float = 1.0) -> Iterator[list[Row]]:  # fmt: skip
    """Answer ``rows`` on the Ray cluster at ``address`` (see `connect`) with ``workers`` actors, batch by batch as
    they finish (any order). The rows of a batch given up after `MAX_TASK_RETRIES` run again one per batch, so
    only a row that kills its actor every time is left out."""
    import ray

    if not rows:
        return
    started = connect(address)
    try:
        context = ray.data.DataContext.get_current()
        context.enable_progress_bars = False  # the caller shows one bar of items
        context.max_errored_blocks = -1  # a batch given up must not stop the others; its rows count as missing
        answered: set[str] = set()
        for batch in _pass(rows, factory, workers, batch_size, cpus_per_worker):
            answered.update(str(row["id"]) for row in batch)
            yield batch
        lost = [row for row in rows if str(row["id"]) not in answered]
        if lost and batch_size > 1:
            yield from _pass(lost, factory, workers, 1, cpus_per_worker)
    finally:
        if started:
            ray.shutdown()


def _pass(rows: list[Row], factory: WorkerFactory, workers: int, batch_size: int,
          cpus_per_worker: float) -> Iterator[list[Row]]:  # fmt: skip
    """One Ray Data pipeline over ``rows``: a block a batch, an actor pool of ``workers``, streamed back."""
    import ray

    dataset = ray.data.from_items(rows, override_num_blocks=math.ceil(len(rows) / max(1, batch_size)))
    with warnings.catch_warnings():  # Ray 2.60 names no parameter for max_task_retries but these remote args
        warnings.filterwarnings("ignore", message=".*ray_remote_args.* is deprecated")
        answered = dataset.map_batches(
            _Actor, fn_constructor_args=(factory,), batch_size=batch_size, batch_format="numpy",
            compute=ray.data.ActorPoolStrategy(size=max(1, min(workers, len(rows)))), num_cpus=cpus_per_worker,
            max_restarts=-1, max_task_retries=MAX_TASK_RETRIES,
        )  # fmt: skip
    for batch in answered.iter_batches(batch_size=None, batch_format="numpy"):
        yield rows_of(batch)
