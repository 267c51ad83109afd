"""Optional bearer API keys, the tenant each key is, and a per-key token bucket (per client address when keys
are off).

Tenancy: with keys configured every key is a tenant; its id is a hash of the key (stable across replicas and
restarts, never the key itself), stored with each job, batch and registered robot it creates. A tenant's reads see
only its own (anything else answers 404, like an unknown id); an admin key (``MANI_ADMIN_KEYS``) reads everyone's.
Without keys there is one tenant, ``None``, and everything is visible, as before.
"""

from __future__ import annotations

import hashlib
import hmac
import time
from collections import OrderedDict
from dataclasses import dataclass

from manifoundation.server.api.errors import RateLimited, Unauthorized

MAX_BUCKETS = 10_000  # identities remembered; the least recently used bucket is forgotten first


def check_key(authorization: str | None, keys: list[str]) -> str:
    """The key presented in ``Authorization: Bearer <key>`` when it is one of ``keys``.

    Raises:
        Unauthorized: no header, another scheme, or an unknown key.
    """
    if not authorization:
        raise Unauthorized("missing API key: send 'Authorization: Bearer <key>'")
    scheme, _, token = authorization.partition(" ")
    token = token.strip()
    if scheme.lower() != "bearer" or not token:
        raise Unauthorized("Authorization must be 'Bearer <key>'")
    for key in keys:
        if hmac.compare_digest(key.encode(), token.encode()):
            return key
    raise Unauthorized("unknown API key")


@dataclass(frozen=True)
class Caller:
    """Who is calling: ``tenant`` (None without keys) and whether the key is an admin's."""

    tenant: str | None = None
    admin: bool = False

    @property
    def scope(self) -> str | None:
        """The owner filter of reads: the tenant, or None (everything) for an admin or without keys."""
        return None if self.admin else self.tenant


def tenant_of(key: str) -> str:
    """The tenant id of an API key: 16 hex characters of its SHA-256 (not reversible to the key)."""
    return hashlib.sha256(key.encode()).hexdigest()[:16]


@dataclass
class _Bucket:
    tokens: float
    stamp: float


class RateLimiter:
    """Token buckets keyed by identity: ``rate`` tokens a second up to ``burst``; one request takes one."""

    def __init__(self, rate: float, burst: int) -> None:
        self.rate = rate
        self.burst = float(burst)
        self._buckets: OrderedDict[str, _Bucket] = OrderedDict()

    @property
    def enabled(self) -> bool:
        """Whether requests are limited at all (rate 0: off)."""
        return self.rate > 0

    def blocked(self, identity: str, now: float | None = None) -> float:
        """Seconds until ``identity`` has a token again (0: it has one now); takes nothing."""
        if not self.enabled or identity not in self._buckets:
            return 0.0
        now = time.monotonic() if now is None else now
        bucket = self._buckets[identity]
        tokens = min(self.burst, bucket.tokens + (now - bucket.stamp) * self.rate)
        return 0.0 if tokens >= 1.0 else (1.0 - tokens) / self.rate

    def take(self, identity: str, now: float | None = None) -> None:
        """Take one token for ``identity``.

        Raises:
            RateLimited: the bucket is empty; Retry-After says when the next token arrives.
        """
        if not self.enabled:
            return
        now = time.monotonic() if now is None else now
        bucket = self._buckets.pop(identity, None) or _Bucket(self.burst, now)
        bucket.tokens = min(self.burst, bucket.tokens + (now - bucket.stamp) * self.rate)
        bucket.stamp = now
        self._buckets[identity] = bucket
        while len(self._buckets) > MAX_BUCKETS:
            self._buckets.popitem(last=False)
        if bucket.tokens < 1.0:
            wait = (1.0 - bucket.tokens) / self.rate
            raise RateLimited(f"rate limit of {self.rate:g} requests/s (burst {self.burst:g}) exceeded", wait)
        bucket.tokens -= 1.0
