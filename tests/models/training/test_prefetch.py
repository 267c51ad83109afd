"""`made_ahead`: the same items in the same order, the next one made while this one is used."""

from __future__ import annotations

import threading
import time
from collections.abc import Callable

import numpy as np

from models.training.prefetch import made_ahead


def test_items_come_in_order_with_the_same_random_draws() -> None:
    def draw(rng: np.random.Generator) -> float:
        return float(rng.random())

    plain = [draw(r) for r in [np.random.default_rng(0)] * 5]
    rng = np.random.default_rng(0)
    ahead = list(made_ahead(lambda _i: draw(rng), range(5)))
    assert ahead == plain


def test_the_next_item_is_made_while_this_one_is_used() -> None:
    started: list[int] = []
    made_in: set[str] = set()

    def make(i: int) -> int:
        started.append(i)
        made_in.add(threading.current_thread().name)
        return i

    it = made_ahead(make, range(3))
    assert next(it) == 0
    time.sleep(0.05)
    assert started == [0, 1]  # item 1 was started before we asked for it
    assert list(it) == [1, 2]
    assert all(name.startswith("batch") for name in made_in)


def recorder(started: list[int]) -> Callable[[int], int]:
    def make(i: int) -> int:
        started.append(i)
        return i

    return make


def test_closing_early_makes_no_more_than_one_extra() -> None:
    started: list[int] = []
    it = made_ahead(recorder(started), range(100))
    assert next(it) == 0
    it.close()
    assert len(started) <= 2


def test_disabled_makes_each_item_when_asked() -> None:
    started: list[int] = []
    it = made_ahead(recorder(started), range(3), enabled=False)
    assert next(it) == 0 and started == [0]
