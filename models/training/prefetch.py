"""Training batches made one ahead, in a thread, while the current step runs.

A batch is built in numpy (`models.data.dataset.make_batch`: the grasp sets' heatmaps, the masks, the rotations),
about a fifth of a CPU step; most of it releases the GIL, so the next batch can be built while torch computes
this one. One producer thread builds the batches in order, so the random draws of augmentation happen in the same
sequence as without it and a run gives the same losses.
"""

from __future__ import annotations

from collections.abc import Callable, Generator, Iterable
from concurrent.futures import Future, ThreadPoolExecutor
from typing import TypeVar

Item = TypeVar("Item")
Made = TypeVar("Made")


def made_ahead(
    make: Callable[[Item], Made], items: Iterable[Item], enabled: bool = True
) -> Generator[Made, None, None]:
    """``make(item)`` for each item in order; with ``enabled`` the next one is being made while this is used.

    Closing the iterator early (a time budget ends the epoch) waits for the one batch being made, no more.
    """
    if not enabled:
        yield from (make(item) for item in items)
        return
    with ThreadPoolExecutor(max_workers=1, thread_name_prefix="batch") as pool:
        pending: Future[Made] | None = None
        for item in items:
            upcoming = pool.submit(make, item)
            if pending is not None:
                yield pending.result()
            pending = upcoming
        if pending is not None:
            yield pending.result()
