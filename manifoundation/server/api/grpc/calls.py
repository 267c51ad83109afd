"""What every RPC does around its own work: the caller's key and rate, metrics, the error translation, and the
reported versions (``x-mani-contract-version``, ``x-mani-service-version``) in the initial metadata of every call
(and in the trailers of a failed one).

The same rules as HTTP (`manifoundation.server.api.deps.authorize`), on the app's own objects: the keys of `Settings`,
the tenant of each key (`manifoundation.server.api.security.tenant_of`), one token bucket per key shared by both
transports (a key's HTTP and gRPC calls draw on the same bucket), and the same wrong-key limit per client address. The
key travels in the ``authorization`` metadata as ``Bearer <key>``. Health checks and reflection need no key (like
/healthz).
"""

from __future__ import annotations

import asyncio
import contextvars
import functools
import time
from collections.abc import AsyncIterator, Awaitable, Callable
from typing import TYPE_CHECKING, Any, TypeVar

import grpc
from prometheus_client import Counter, Histogram

from manifoundation.server.api.errors import RateLimited, Unauthorized
from manifoundation.server.api.grpc.errors import abort, code_of, translate
from manifoundation.server.api.metrics import LATENCY_BUCKETS, Metrics
from manifoundation.server.api.security import Caller, RateLimiter, check_key, tenant_of
from manifoundation.server.api.settings import Settings

if TYPE_CHECKING:
    from manifoundation.server.api.services import AppServices

Reply = TypeVar("Reply")
_initial_sent: contextvars.ContextVar[bool] = contextvars.ContextVar("grpc_initial_metadata_sent", default=False)


class GrpcMetrics:
    """gRPC calls by method and code, and their latency, in the app's registry beside the HTTP ones."""

    def __init__(self, metrics: Metrics) -> None:
        self.requests = Counter(
            "mani_grpc_requests",
            "gRPC calls by method and status code.",
            ["method", "code"],
            registry=metrics.registry,
        )
        self.duration = Histogram(
            "mani_grpc_request_duration_seconds",
            "gRPC call latency (until the last message).",
            ["method"],
            buckets=LATENCY_BUCKETS,
            registry=metrics.registry,
        )

    def observe(self, method: str, code: grpc.StatusCode, started: float) -> None:
        """Count one finished call."""
        self.requests.labels(method, code.name).inc()
        self.duration.labels(method).observe(time.perf_counter() - started)


def peer_address(context: grpc.aio.ServicerContext) -> str:
    """The client's address without its port (``ipv4:1.2.3.4:5678`` → ``1.2.3.4``)."""
    peer = context.peer() or "unknown"
    _, _, address = peer.partition(":")
    host = address.rsplit(":", 1)[0] if address.count(":") >= 1 else address
    return host.strip("[]") or peer


def authorize(services: AppServices, context: grpc.aio.ServicerContext) -> Caller:
    """The caller of this RPC, after its key (when keys are set) and its token bucket.

    Raises:
        Unauthorized: missing or unknown key.
        RateLimited: too many wrong keys from this address, or the caller's rate is over its limit.
    """
    settings: Settings = services.settings
    identity = peer_address(context)
    caller = Caller()
    if settings.auth_enabled:
        failures: RateLimiter = services.auth_failures
        if wait := failures.blocked(identity):
            raise RateLimited("too many requests with a wrong API key from this address", wait)
        metadata = {k.lower(): v for k, v in context.invocation_metadata() or ()}
        header = metadata.get("authorization")
        try:
            key = check_key(header if isinstance(header, str) else None, settings.all_keys)
        except Unauthorized:
            failures.take(identity)
            raise
        identity = "key:" + key
        caller = Caller(tenant=tenant_of(key), admin=key in settings.admin_keys)
    limiter: RateLimiter = services.limiter
    limiter.take(identity)
    return caller


async def send_initial_metadata(
    services: AppServices, context: grpc.aio.ServicerContext, *pairs: tuple[str, str]
) -> None:
    """Send the call's initial metadata now: the reported versions and ``pairs`` (once per call: an RPC that
    sends its own, e.g. a job id, calls this instead of ``context.send_initial_metadata``)."""
    await context.send_initial_metadata((*services.versions.metadata(), *pairs))
    _initial_sent.set(True)


async def _announce(services: AppServices, context: grpc.aio.ServicerContext) -> None:
    """The versions in the initial metadata, unless the RPC already sent its own."""
    if not _initial_sent.get():
        await send_initial_metadata(services, context)


Unary = Callable[[Any, Any, grpc.aio.ServicerContext, Caller], Awaitable[Reply]]
Streaming = Callable[[Any, Any, grpc.aio.ServicerContext, Caller], AsyncIterator[Reply]]


def unary(handler: Unary[Reply]) -> Callable[[Any, Any, grpc.aio.ServicerContext], Awaitable[Reply]]:
    """An RPC method: authorise, run ``handler(self, request, context, caller)``, translate its errors once."""

    @functools.wraps(handler)
    async def call(self: Any, request: Any, context: grpc.aio.ServicerContext) -> Reply:
        started, code = time.perf_counter(), grpc.StatusCode.OK
        _initial_sent.set(False)
        try:
            reply = await handler(self, request, context, authorize(self.services, context))
            await _announce(self.services, context)
            return reply
        except asyncio.CancelledError:  # the client cancelled, went away or its deadline passed
            code = grpc.StatusCode.CANCELLED
            raise
        except Exception as exc:
            code = code_of(translate(exc)[0])
            await abort(context, exc, self.services.versions.metadata())
        finally:
            self.metrics.observe(handler.__name__, code, started)

    return call


def streaming(handler: Streaming[Reply]) -> Callable[[Any, Any, grpc.aio.ServicerContext], AsyncIterator[Reply]]:
    """A server-streaming RPC method: as `unary`, for an async generator."""

    @functools.wraps(handler)
    async def call(self: Any, request: Any, context: grpc.aio.ServicerContext) -> AsyncIterator[Reply]:
        started, code = time.perf_counter(), grpc.StatusCode.OK
        _initial_sent.set(False)
        try:
            async for reply in handler(self, request, context, authorize(self.services, context)):
                await _announce(self.services, context)
                yield reply
            await _announce(self.services, context)  # a stream that sent nothing
        except asyncio.CancelledError:  # the client cancelled, went away or its deadline passed
            code = grpc.StatusCode.CANCELLED
            raise
        except Exception as exc:
            code = code_of(translate(exc)[0])
            await abort(context, exc, self.services.versions.metadata())
        finally:
            self.metrics.observe(handler.__name__, code, started)

    return call
