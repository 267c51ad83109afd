"""Give the C heap's free pages back to the operating system between micro-batches.

A request allocates and frees tens of MB (the network's activations, the refinement's arrays); glibc keeps most
freed memory in its arenas, so a worker's resident size stays near its largest request's peak. `malloc_trim(0)`
returns the free pages (≈ 25 MB of a LEAP worker's 600, 2-3 ms a call); the core calls it at most once every
``TRIM_INTERVAL_S`` so that a busy worker pays ≈ 0.1 % of its time for it.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import time
from collections.abc import Callable

TRIM_INTERVAL_S = 2.0
"""Seconds between trims at most."""


def _malloc_trim() -> Callable[[int], int] | None:
    """glibc's ``malloc_trim``, or None where the C library has none (macOS, musl)."""
    name = ctypes.util.find_library("c")
    try:
        trim: Callable[[int], int] = ctypes.CDLL(name).malloc_trim
    except (OSError, AttributeError, TypeError):
        return None
    return trim


class HeapTrimmer:
    """Calls ``malloc_trim(0)`` when asked, if ``interval`` seconds have passed since the last call."""

    def __init__(self, interval: float = TRIM_INTERVAL_S, clock: Callable[[], float] = time.monotonic) -> None:
        self.interval = interval
        self.clock = clock
        self._trim = _malloc_trim()
        self._last = -float("inf")
        self.trims = 0

    def maybe_trim(self) -> bool:
        """Trim now if due; True when it did."""
        now = self.clock()
        if self._trim is None or now - self._last < self.interval:
            return False
        self._last = now
        self._trim(0)
        self.trims += 1
        return True
