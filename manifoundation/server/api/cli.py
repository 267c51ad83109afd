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
ports: both are checked before anything loads. A taken default port (HTTP 8000, gRPC 50051) is replaced by a
  free one, printed at start; a port you set (--port, MANI_PORT, --grpc-port, MANI_GRPC_PORT) must be free.
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


class PortTaken(Exception):
    """A port `mani serve` was told to use cannot be listened on; the message is the one line to print."""


def _cannot_listen(host: str, port: int) -> str | None:
    """Why ``host:port`` cannot be listened on now (another process holds it, or the address is not ours); None: it
    can. Bound the way uvicorn and gRPC bind (``SO_REUSEADDR``, no ``SO_REUSEPORT``) and released at once."""
    import socket

    family = socket.AF_INET6 if ":" in host else socket.AF_INET
    with socket.socket(family, socket.SOCK_STREAM) as sock:
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            sock.bind((host, port))
        except OSError as exc:
            return exc.strerror or str(exc)
    return None


def _free_port(host: str, avoid: int) -> int:
    """A port the system has free on ``host`` now, other than ``avoid`` (the HTTP port, not bound yet)."""
    import socket

    family = socket.AF_INET6 if ":" in host else socket.AF_INET
    while True:
        with socket.socket(family, socket.SOCK_STREAM) as sock:
            sock.bind((host, 0))
            port = int(sock.getsockname()[1])
        if port != avoid:
            return port


def check_ports(settings: Any) -> tuple[Any, list[str]]:
    """``settings`` once both ports are known to be free, and the lines to print for ports that moved; `PortTaken`
    when a port the user set (``--port`` / ``MANI_PORT``, ``--grpc-port`` / ``MANI_GRPC_PORT``) cannot be listened
    on. A taken *default* port (8000, 50051) is replaced by a free one, as Jupyter does, so the README's first
    command runs on a busy machine. Run before anything loads, so a busy port costs a second, not the model
    loading."""
    notes: list[str] = []
    if settings.port:
        why = _cannot_listen(settings.host, settings.port)
        if why and "port" in settings.model_fields_set:
            raise PortTaken(f"mani serve: cannot listen on {settings.host}:{settings.port} ({why}): choose another "
                            "port with --port or MANI_PORT (make serve PORT=...)")  # fmt: skip
        if why:
            port = _free_port(settings.host, settings.grpc_port)
            notes.append(f"mani serve: port {settings.port} is taken ({why}); the service listens on "
                         f"http://{settings.host}:{port} instead: point clients there (--url, MANI_URL) or choose "
                         "with --port or MANI_PORT (make serve PORT=...)")  # fmt: skip
            settings = settings.model_copy(update={"port": port})
    if not settings.grpc_port:
        return settings, notes
    host = settings.grpc_host or settings.host
    same = settings.port and settings.grpc_port == settings.port and host == settings.host
    why = "the HTTP port" if same else _cannot_listen(host, settings.grpc_port)
    if not why:
        return settings, notes
    if "grpc_port" in settings.model_fields_set:
        raise PortTaken(f"mani serve: cannot listen for gRPC on {host}:{settings.grpc_port} ({why}): choose another "
                        "port with --grpc-port or MANI_GRPC_PORT (make serve GRPC_PORT=...), or --no-grpc")  # fmt: skip
    port = _free_port(host, settings.port)
    notes.append(f"mani serve: gRPC port {settings.grpc_port} is taken ({why}); gRPC listens on {host}:{port} "
                 "instead (choose with --grpc-port or MANI_GRPC_PORT, make serve GRPC_PORT=...; "
                 "--no-grpc: none)")  # fmt: skip
    return settings.model_copy(update={"grpc_port": port}), notes


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

    from pydantic import ValidationError

    try:
        settings, moved = check_ports(settings_from(args))
    except ValidationError as exc:
        print(f"mani serve: invalid settings:\n{exc}", file=sys.stderr)
        return 2
    except PortTaken as exc:
        print(exc, file=sys.stderr)
        return 2
    for line in moved:
        print(line, file=sys.stderr, flush=True)

    import uvicorn

    from manifoundation.server.api.app import configure_logging, create_app
    from manifoundation.server.api.services import services_of

    configure_logging(settings)
    app = create_app(settings, grpc=True)

    class Server(uvicorn.Server):
        def handle_exit(self, sig: int, frame: Any) -> None:
            services_of(app).shutting_down = True
            super().handle_exit(sig, frame)

    server = Server(uvicorn_config(app, settings))
    server.run()
    return 0 if server.started else 1
