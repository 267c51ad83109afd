"""`mani mcp`: the MCP tools over stdio, for an agent on this machine, in front of a running service.

The tools are the same as at ``/mcp`` on the service (`manifoundation.server.api.mcp.tools`); here they call the service
over HTTP with the SDK (`ClientBackend`) with the key given (``--api-key`` / ``MANI_API_KEY``), so the service
validates, limits and scopes every call as it does any SDK call. Uploaded objects stay in this process (the
``MANI_OBJECT_TTL_S`` / ``MANI_MAX_OBJECTS`` / ``MANI_MAX_OBJECT_STORE_BYTES`` limits) and may also be read from files
on this machine (``upload_object(path=...)``). Stdout carries the protocol; logs go to stderr.

Kept light at import time: the MCP SDK is imported when the command runs.
"""

from __future__ import annotations

import argparse
import logging
import os
import sys
from typing import Any

DEFAULT_URL = "http://127.0.0.1:8000"
EXAMPLE = """example (an MCP client's server entry):
  {"command": "mani", "args": ["mcp", "--url", "http://127.0.0.1:8000"], "env": {"MANI_API_KEY": "..."}}"""


def register(subparsers: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Add the ``mcp`` sub-command."""
    parser = subparsers.add_parser(
        "mcp",
        help="serve the MCP tools over stdio (for a local LLM agent), calling a running service",
        description=__doc__.splitlines()[0] if __doc__ else None,
        epilog=EXAMPLE,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("--url", default=os.environ.get("MANI_URL", DEFAULT_URL),
                        help="service base URL (env MANI_URL; default %(default)s)")  # fmt: skip
    parser.add_argument("--api-key", default=os.environ.get("MANI_API_KEY"), help="bearer API key (env MANI_API_KEY)")
    parser.add_argument("--log-level", default="WARNING", help="stderr log level (default %(default)s)")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Serve over stdio until the client closes it."""
    import anyio

    logging.basicConfig(level=args.log_level.upper(), stream=sys.stderr, format="%(levelname)s %(name)s %(message)s")
    anyio.run(serve_stdio, args.url, args.api_key)
    return 0


async def serve_stdio(url: str, api_key: str | None) -> None:
    """The tool server on this process's stdin/stdout, its backend the SDK against ``url``."""
    from manifoundation.sdk import AsyncClient
    from manifoundation.server.api.mcp.backend import ClientBackend
    from manifoundation.server.api.mcp.objects import ObjectStore
    from manifoundation.server.api.mcp.tools import Session, build_server
    from manifoundation.server.api.settings import Settings

    settings = Settings()
    objects = ObjectStore(settings.object_ttl_s, settings.max_objects, settings.max_object_store_bytes)
    async with AsyncClient(url, api_key, encoding="msgpack") as client:
        session = Session(ClientBackend(client), tenant="local", files=True)

        async def session_of(ctx: Any) -> Session:
            return session

        try:
            await build_server(objects, session_of).run_stdio_async()
        finally:
            objects.close()
