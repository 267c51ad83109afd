"""What the client-side `mani` commands share: connection options, the client, output, errors → exit codes.

Kept light at import time (argparse only): the SDK, httpx, rich and tqdm are imported when a command runs.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from manifoundation.cli.main import EXIT_FAILED, EXIT_OK, EXIT_UNREACHABLE, EXIT_USAGE

if TYPE_CHECKING:
    from manifoundation.sdk import Client
    from manifoundation.sdk.grpc_client import GrpcClient

DEFAULT_URL = "http://127.0.0.1:8000"
EXIT_CODES_HELP = (
    "exit codes: 0 done, 1 the work failed (job failed, timed out, server error), "
    "2 invalid input or usage (the message names the field), 3 service unreachable, 130 interrupted"
)


def add_connection_args(parser: argparse.ArgumentParser, *, json_flag: bool = True, grpc: bool = False) -> None:
    """``--url``, ``--api-key``, ``--encoding``, ``--retries`` (and ``--json``) for a command talking to a service;
    ``grpc``: ``--grpc HOST:PORT`` too, for a command that can send over either transport (see `job_client`)."""
    group = parser.add_argument_group("service")
    group.add_argument(
        "--url",
        default=os.environ.get("MANI_URL", DEFAULT_URL),
        help="service base URL (env MANI_URL; default %(default)s)",
    )
    if grpc:
        group.add_argument(
            "--grpc",
            metavar="HOST:PORT",
            help="send over gRPC to the service's gRPC port (e.g. 127.0.0.1:50051) instead of HTTP to --url; "
            "--api-key and --retries apply, --encoding does not (needs the [grpc] extra)",
        )
    group.add_argument("--api-key", default=os.environ.get("MANI_API_KEY"), help="bearer API key (env MANI_API_KEY)")
    group.add_argument(
        "--encoding", choices=("msgpack", "json"), default="msgpack", help="wire encoding (default %(default)s)"
    )
    group.add_argument("--retries", type=int, default=3, help="retries on 429/503/connection errors (default 3)")
    if json_flag:
        parser.add_argument("--json", action="store_true", help="print machine-readable JSON on stdout")


def command_parser(
    subparsers: argparse._SubParsersAction[argparse.ArgumentParser],
    name: str,
    help: str,
    example: str,
    func: Callable[[argparse.Namespace], int] | None = None,
) -> argparse.ArgumentParser:
    """A sub-parser whose ``--help`` ends with an example and the exit codes."""
    parser = subparsers.add_parser(
        name,
        help=help,
        description=help,
        epilog=f"example:\n  {example}\n\n{EXIT_CODES_HELP}",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    if func is not None:
        parser.set_defaults(func=func)
    return parser


# Factory of the SDK client; tests replace it to inject a transport.
def make_client(args: argparse.Namespace) -> Client:
    """The SDK client for a command's connection options."""
    from manifoundation.sdk import Client

    return Client(args.url, args.api_key, encoding=args.encoding, retries=max(0, args.retries))


client_factory: Callable[[argparse.Namespace], Client] = make_client


def make_grpc_client(args: argparse.Namespace) -> GrpcClient:
    """The SDK's gRPC client for ``--grpc HOST:PORT`` and the command's ``--api-key`` and ``--retries``.

    Raises:
        MissingExtra: the ``[grpc]`` extra is not installed.
    """
    from manifoundation.sdk.grpc_client import GrpcClient

    return GrpcClient(args.grpc, args.api_key, retries=max(0, args.retries))


grpc_client_factory: Callable[[argparse.Namespace], GrpcClient] = make_grpc_client


def job_client(args: argparse.Namespace) -> Client | GrpcClient:
    """The client of a command that runs jobs over either transport: gRPC with ``--grpc``, else HTTP.

    Both are the SDK's one synchronous surface (`manifoundation.sdk._api.SyncAPI`): the same calls, handles and
    results, so the command's output is the same whichever carried it.
    """
    return grpc_client_factory(args) if getattr(args, "grpc", None) else client_factory(args)


def run_guarded(func: Callable[[argparse.Namespace], int]) -> Callable[[argparse.Namespace], int]:
    """Wrap a command: SDK errors become a one-line message on stderr and a meaningful exit code."""

    def wrapper(args: argparse.Namespace) -> int:
        from manifoundation.sdk import JobFailed, ManiError, RequestError, ServerError, Unreachable

        try:
            return func(args)
        except Unreachable as exc:
            return fail(args, exc, EXIT_UNREACHABLE)
        except ServerError as exc:
            return fail(args, exc, EXIT_FAILED)
        except RequestError as exc:
            return fail(args, exc, EXIT_USAGE)
        except JobFailed as exc:
            return fail(args, exc, EXIT_FAILED)
        except ManiError as exc:
            return fail(args, exc, EXIT_FAILED)
        except (FileNotFoundError, IsADirectoryError, ValueError, TypeError) as exc:
            return fail(args, exc, EXIT_USAGE)

    wrapper.__name__ = func.__name__
    wrapper.__doc__ = func.__doc__
    return wrapper


def fail(args: argparse.Namespace, exc: BaseException, code: int) -> int:
    """Report an error (JSON on stdout with ``--json``, text on stderr always) and return ``code``."""
    from manifoundation.sdk import JobFailed, RequestError

    body: dict[str, Any] = {
        "error": str(exc).splitlines()[0] if str(exc) else type(exc).__name__,
        "type": type(exc).__name__,
    }
    if isinstance(exc, RequestError):
        body.update(type=exc.type, status=exc.status_code)
        if exc.detail:
            body["detail"] = [d.model_dump() for d in exc.detail]
    if isinstance(exc, JobFailed):
        body.update(job_id=exc.job_id, state=exc.state.value)
        if exc.error is not None:
            body["job_error"] = exc.error.model_dump(exclude_none=True)
    job_id = getattr(exc, "job_id", None)
    if job_id:
        body["job_id"] = job_id
    if getattr(args, "json", False):
        print_json(body)
    print(f"mani: error: {exc}", file=sys.stderr)
    return code


def print_json(data: Any) -> None:
    """Print JSON on stdout (one document)."""
    sys.stdout.write(json.dumps(data, indent=2, default=str) + "\n")
    sys.stdout.flush()


TABLE_WIDTH = 100
"""Columns a table may use when the output is not a terminal (a pipe or a file: rich would assume 80)."""


def stderr_console() -> Any:
    """A rich console on stderr (progress and tables never mix with ``--json`` output on stdout)."""
    return _console(stderr=True)


def stdout_console() -> Any:
    """A rich console on stdout for human-readable output."""
    return _console(stderr=False)


def _console(stderr: bool) -> Any:
    """A rich console, ``TABLE_WIDTH`` columns wide when its stream is not a terminal."""
    from rich.console import Console

    console = Console(stderr=stderr)
    if not console.is_terminal:
        console.width = TABLE_WIDTH
    return console


__all__ = [
    "DEFAULT_URL",
    "EXIT_FAILED",
    "EXIT_OK",
    "EXIT_UNREACHABLE",
    "EXIT_USAGE",
    "add_connection_args",
    "client_factory",
    "command_parser",
    "fail",
    "grpc_client_factory",
    "job_client",
    "make_client",
    "make_grpc_client",
    "print_json",
    "run_guarded",
]
