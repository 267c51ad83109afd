"""Retry and polling policy (no I/O): exponential backoff with jitter, Retry-After, which failures are retried."""

from __future__ import annotations

import email.utils
import random
import time
from collections.abc import Iterator
from dataclasses import dataclass

import httpx

# Answers worth retrying: any method (the request was refused, not accepted) ...
RETRY_STATUSES = frozenset({429, 503})
# ... and, for idempotent methods, gateway failures too.
RETRY_STATUSES_IDEMPOTENT = frozenset({429, 502, 503, 504})
IDEMPOTENT_METHODS = frozenset({"GET", "HEAD", "DELETE", "OPTIONS"})
# Transport errors where the request surely did not reach the service: safe to retry any method.
NOT_SENT = (httpx.ConnectError, httpx.ConnectTimeout, httpx.PoolTimeout)
# Transport errors after sending: retried only for idempotent methods (never duplicate a job).
MAYBE_SENT = (httpx.ReadError, httpx.WriteError, httpx.RemoteProtocolError)


@dataclass(frozen=True)
class RetryPolicy:
    """Retries with exponential backoff and jitter on 429/503 and connection errors.

    The n-th retry waits ``min(max_backoff, backoff * 2**n)`` scaled by a random factor in
    ``[1 - jitter, 1]``, or the service's Retry-After when that is longer (capped at ``max_retry_after``).

    Attributes:
        max_retries: retries after the first attempt (0 disables retrying).
        backoff: first delay, seconds.
        max_backoff: largest computed delay, seconds.
        jitter: fraction of the delay drawn at random (0: none, 1: "full jitter").
        max_retry_after: largest Retry-After honoured, seconds.
    """

    max_retries: int = 3
    backoff: float = 0.25
    max_backoff: float = 8.0
    jitter: float = 0.5
    max_retry_after: float = 60.0

    def delay(self, retry: int, retry_after: float | None = None, rng: random.Random | None = None) -> float:
        """Seconds to wait before retry number ``retry`` (0-based)."""
        base = min(self.max_backoff, self.backoff * (2**retry))
        draw = (rng or random).random()
        wait = base * (1.0 - self.jitter * draw)
        if retry_after is not None:
            wait = max(wait, min(retry_after, self.max_retry_after))
        return wait


def parse_retry_after(value: str | None, now: float | None = None) -> float | None:
    """Seconds from a Retry-After header (delta-seconds or an HTTP date); None when absent or unreadable."""
    if not value:
        return None
    value = value.strip()
    try:
        return max(0.0, float(value))
    except ValueError:
        pass
    try:
        when = email.utils.parsedate_to_datetime(value)
    except (TypeError, ValueError):
        return None
    return max(0.0, when.timestamp() - (time.time() if now is None else now))


def poll_delays(first: float = 0.05, factor: float = 1.5, cap: float = 1.0) -> Iterator[float]:
    """Growing pause between two status polls: fast for quick jobs, gentle for long ones."""
    delay = first
    while True:
        yield delay
        delay = min(cap, delay * factor)


DEFAULT_RETRY = RetryPolicy()
