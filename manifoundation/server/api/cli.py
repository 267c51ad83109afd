"""`mani serve`: the HTTP API (and gRPC beside it), with embedded workers (default) or in front of a Redis queue.

Kept light at import time: FastAPI, uvicorn and the queue are imported when the command runs.
"""

from __future__ import annotations

import argparse
from typing import Any

EXAMPLE = """examples:
  mani serve                                  # API + 2 embedded worker processes on 127.0.0.1:8000
  mani serve --port 9000 --workers 4
  mani serve --redis redis://localhost:6379/0 # API only; run `mani worker --redis ...` elsewhere
  mani serve --grpc-port 50052                # gRPC on another port (default 50051; --no-grpc: HTTP only)
environment: MANI_HOST, MANI_PORT, MANI_GRPC_PORT, MANI_GRPC_MAX_MESSAGE_BYTES, MANI_CONCURRENCY,
  MANI_REDIS_URL, MANI_API_KEYS, MANI_RATE_LIMIT_PER_S, ..."""


def register(subparsers: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Add the ``serve`` sub-command."""
    parser = subparsers.add_parser(
        "serve",
        help="run the HTTP service",
        description=__doc__.splitlines()[0] if __doc__ else None,
        epilog=EXAMPLE,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("--host", help="address to listen on (MANI_HOST, default 127.0.0.1)")
    parser.add_argument("--port", type=int, help="port (MANI_PORT, default 8000)")
    parser.add_argument("--workers", type=int, help="embedded worker processes (MANI_CONCURRENCY, default 2)")
    parser.add_argument("--redis", metavar="URL", help="Redis URL: API only, workers run as `mani worker`")
    grpc = parser.add_mutually_exclusive_group()
    grpc.add_argument(
        "--grpc-port",
        type=int,
        help="gRPC port beside HTTP, same process and queue (MANI_GRPC_PORT, default 50051; 0: off)",
    )
    grpc.add_argument("--no-grpc", action="store_true", help="serve HTTP only (same as --grpc-port 0)")
    parser.add_argument("--log-level", help="DEBUG, INFO, WARNING, ... (MANI_LOG_LEVEL)")
    parser.set_defaults(func=serve)


def settings_from(args: argparse.Namespace) -> Any:
    """`Settings` from the environment with the command line on top."""
    from manifoundation.server.api.settings import Settings

    grpc_port = 0 if getattr(args, "no_grpc", False) else getattr(args, "grpc_port", None)
    given = {
        "host": args.host,
        "port": args.port,
        "log_level": getattr(args, "log_level", None),
        "grpc_port": grpc_port,
    }
    queue = {"concurrency": args.workers, "redis_url": args.redis}
    return Settings(
        **{k: v for k, v in given.items() if v is not None}, queue={k: v for k, v in queue.items() if v is not None}
    )


def uvicorn_config(app: Any, settings: Any) -> Any:
    """uvicorn's configuration for ``app``: X-Forwarded-For believed only from ``forwarded_allow_ips`` (uvicorn's
    default believes it from 127.0.0.1, so any local client could pose as any address); request heads bounded
    by ``header_timeout`` (`manifoundation.server.api.http_protocol`)."""
    import uvicorn

    from manifoundation.server.api.http_protocol import bounded_head_protocol

    return uvicorn.Config(
        app,
        host=settings.host,
        port=settings.port,
        access_log=False,
        log_config=None,
        timeout_graceful_shutdown=10,
        timeout_keep_alive=5,
        lifespan="on",
        http=bounded_head_protocol(settings.header_timeout),
        proxy_headers=settings.forwarded_allow_ips is not None,
        forwarded_allow_ips=settings.forwarded_allow_ips or "",
    )


def serve(args: argparse.Namespace) -> int:
    """Run uvicorn until SIGINT/SIGTERM; new `/v1` requests get 503 as soon as shutdown starts."""
    import sys

    import uvicorn
    from pydantic import ValidationError

    from manifoundation.server.api.app import configure_logging, create_app

    try:
        settings = settings_from(args)
    except ValidationError as exc:
        print(f"mani serve: invalid settings:\n{exc}", file=sys.stderr)
        return 2
    configure_logging(settings)
    app = create_app(settings, grpc=True)

    class Server(uvicorn.Server):
        def handle_exit(self, sig: int, frame: Any) -> None:
            app.state.shutting_down = True
            super().handle_exit(sig, frame)

    server = Server(uvicorn_config(app, settings))
    server.run()
    return 0 if server.started else 1
