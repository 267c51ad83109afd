"""The worker's heap trim: due at most once an interval, and it gives freed C-heap pages back on glibc."""

from __future__ import annotations

import ctypes
import sys

import pytest

from manifoundation.server.worker.heap import HeapTrimmer


def test_trims_at_most_once_an_interval():
    now = [100.0]
    trimmer = HeapTrimmer(interval=2.0, clock=lambda: now[0])
    if trimmer._trim is None:
        pytest.skip("this C library has no malloc_trim")
    assert trimmer.maybe_trim()  # the first call is due
    now[0] += 1.9
    assert not trimmer.maybe_trim()
    now[0] += 0.2
    assert trimmer.maybe_trim()
    assert trimmer.trims == 2


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="resident size read from /proc")
def test_a_trim_returns_freed_heap_pages():
    trimmer = HeapTrimmer(interval=0.0)
    if trimmer._trim is None:
        pytest.skip("this C library has no malloc_trim")
    libc = ctypes.CDLL(None)
    libc.malloc.restype = ctypes.c_void_p
    libc.free.argtypes = [ctypes.c_void_p]
    # many blocks below the mmap threshold: freed, they stay in the heap until trimmed
    blocks = [libc.malloc(64 * 1024) for _ in range(1600)]  # 100 MiB
    for b in blocks:
        ctypes.memset(b, 1, 64 * 1024)
    for b in blocks[:-1]:  # the last one pins the top of the heap: only a trim returns the pages below it
        libc.free(b)
    before = _rss_mb()
    assert trimmer.maybe_trim()
    assert _rss_mb() < before - 50
    libc.free(blocks[-1])


def _rss_mb() -> float:
    with open("/proc/self/status") as f:
        return int(f.read().split("VmRSS:")[1].split()[0]) / 1024
