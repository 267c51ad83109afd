"""The gRPC server of `mani serve`: grpc.aio on the HTTP app's event loop, started and stopped in its lifespan.

One process serves both transports over one queue object (embedded workers or Redis), one set of limiters and
one metrics registry (docs/grpc.md says why not a process of its own). Besides `manifoundation.v1.ManiFoundation`
it serves:

- ``grpc.health.v1.Health``: ``""`` is SERVING while the process runs (liveness, like /healthz); the service's
  name is SERVING exactly when /readyz would answer 200 (the queue answers and a live worker has its model),
  re-checked every ``health_interval`` seconds; both turn NOT_SERVING when shutdown starts.
- server reflection (``grpc.reflection.v1alpha``), so ``grpcurl`` lists and calls the service without the proto.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
from typing import TYPE_CHECKING, Any

import grpc
from grpc_health.v1 import health_pb2, health_pb2_grpc
from grpc_health.v1._async import HealthServicer
from grpc_reflection.v1alpha import reflection

from manifoundation.contract.protos.v1 import manifoundation_pb2 as pb
from manifoundation.contract.protos.v1 import manifoundation_pb2_grpc as pb_grpc
from manifoundation.server.api.grpc.servicer import ManiFoundationService
from manifoundation.server.api.grpc.submit import deferred
from manifoundation.server.api.settings import Settings

if TYPE_CHECKING:
    from manifoundation.server.api.services import AppServices

log = logging.getLogger("manifoundation.server.api.grpc")
SERVICE_NAME = pb.DESCRIPTOR.services_by_name["ManiFoundation"].full_name
SERVING, NOT_SERVING = health_pb2.HealthCheckResponse.SERVING, health_pb2.HealthCheckResponse.NOT_SERVING


async def ready(queue: Any) -> bool:
    """/readyz's meaning: the queue answers and a live worker has its model loaded."""
    try:
        return bool(await queue.ping()) and any(w.model_loaded for w in await queue.workers())
    except Exception:
        return False


LARGE_REQUESTS: dict[str, type[Any]] = {
    "Synthesize": pb.SynthesisRequest,
    "SubmitJob": pb.SynthesisRequest,
    "SubmitBatch": pb.BatchCreate,
    "SubmitPlan": pb.PlanRequest,
    "RegisterRobot": pb.RobotRegister,
}
"""The RPCs whose message may be large: parsed off the event loop when it is (`grpc.submit.LargeMessage`)."""


class _Handlers:
    """Stands in for a server to receive the generated code's method handlers."""

    def __init__(self) -> None:
        self.service, self.handlers = "", dict[str, Any]()

    def add_generic_rpc_handlers(self, _: Any) -> None:
        pass

    def add_registered_method_handlers(self, service: str, handlers: dict[str, Any]) -> None:
        self.service, self.handlers = service, handlers


def add_servicer(servicer: Any, server: grpc.aio.Server, offload_bytes: int) -> None:
    """The generated ``add_ManiFoundationServicer_to_server``, except that the messages of `LARGE_REQUESTS` larger
    than ``offload_bytes`` reach the servicer unparsed (`deferred`)."""
    generated = _Handlers()
    pb_grpc.add_ManiFoundationServicer_to_server(servicer, generated)
    handlers = {
        name: handler._replace(request_deserializer=deferred(LARGE_REQUESTS[name], offload_bytes))
        if name in LARGE_REQUESTS else handler
        for name, handler in generated.handlers.items()
    }  # fmt: skip
    server.add_generic_rpc_handlers((grpc.method_handlers_generic_handler(generated.service, handlers),))
    server.add_registered_method_handlers(generated.service, handlers)


class GrpcServer:
    """A started grpc.aio server over the app's services; ``port`` is the one it bound."""

    def __init__(self, services: AppServices, settings: Settings) -> None:
        limit = settings.grpc_max_message_bytes
        self.settings = settings
        self.server = grpc.aio.server(
            options=[
                ("grpc.max_receive_message_length", limit),
                ("grpc.max_send_message_length", limit),
                ("grpc.so_reuseport", 0),  # a port in use is an error, not a second server sharing it
                # each stream reads ahead at most MANI_GRPC_STREAM_WINDOW_BYTES (not a window grown by BDP probing):
                # the pieces of a SubmitBatchStream waiting for a large-body slot stay with the client (with BDP
                # probing, 40 × 57.6 MB streamed took the API to 2.4 GB)
                ("grpc.http2.bdp_probe", 0),
                ("grpc.http2.lookahead_bytes", settings.grpc_stream_window_bytes),
            ],
        )
        self.services = services
        self.health = HealthServicer()
        add_servicer(ManiFoundationService(services), self.server, settings.parse_offload_bytes)
        health_pb2_grpc.add_HealthServicer_to_server(self.health, self.server)
        names = (SERVICE_NAME, health_pb2.DESCRIPTOR.services_by_name["Health"].full_name, reflection.SERVICE_NAME)
        reflection.enable_server_reflection(names, self.server)
        address = f"{settings.grpc_host or settings.host}:{settings.grpc_port}"
        try:
            self.port = self.server.add_insecure_port(address)
        except RuntimeError:
            self.port = 0
        if not self.port:
            raise RuntimeError(
                f"gRPC: cannot listen on {address} (in use?): set --grpc-port / MANI_GRPC_PORT, or --no-grpc"
            )
        self.address = address.rsplit(":", 1)[0] + f":{self.port}"
        self._watch: asyncio.Task[None] | None = None

    async def start(self) -> None:
        """Start serving; readiness is checked at once and then every ``grpc_health_interval`` seconds."""
        await self.health.set("", SERVING)
        await self._check()
        await self.server.start()
        self._watch = asyncio.create_task(self._watch_readiness(), name="grpc-readiness")
        limit = self.settings.grpc_max_message_bytes
        log.info("gRPC serving", extra={"address": self.address, "max_message_bytes": limit})

    async def _check(self) -> None:
        await self.health.set(SERVICE_NAME, SERVING if await ready(self.services.queue) else NOT_SERVING)

    async def _watch_readiness(self) -> None:
        while True:
            await asyncio.sleep(self.settings.grpc_health_interval)
            await self._check()

    async def stop(self, grace: float | None = None) -> None:
        """NOT_SERVING everywhere, then stop: calls in flight get ``grace`` seconds before they are cancelled."""
        if self._watch is not None:
            self._watch.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await self._watch
        await self.health.enter_graceful_shutdown()
        await self.server.stop(self.settings.grpc_grace_s if grace is None else grace)
        log.info("gRPC stopped")


async def start_grpc(services: AppServices, settings: Settings) -> GrpcServer:
    """Build and start the gRPC server of an app (its lifespan calls this after the queue started)."""
    server = GrpcServer(services, settings)
    await server.start()
    return server
