"""`mani serve`'s HTTP protocol bounds the request head: a slowly sent (or never sent) head is answered 408 and
closed within ``header_timeout``, while other connections, and a slow body after a complete head, are served."""

from __future__ import annotations

import contextlib
import json
import socket
import threading
import time
from collections.abc import Iterator

import httpx
import uvicorn

from manifoundation.server.api.app import create_app
from manifoundation.server.api.cli import uvicorn_config
from manifoundation.server.api.settings import Settings

from .fakes import FakeQueue
from .helpers import request_body
from .server import free_port

BOUND = 0.5


@contextlib.contextmanager
def _serve() -> Iterator[int]:
    settings = Settings(header_timeout=BOUND, rate_limit_per_s=0, host="127.0.0.1", port=free_port())
    server = uvicorn.Server(uvicorn_config(create_app(settings, queue=FakeQueue()), settings))
    thread = threading.Thread(target=server.run, daemon=True)
    thread.start()
    try:
        while not server.started:
            time.sleep(0.02)
        yield settings.port
    finally:
        server.should_exit = True
        thread.join(30)


def _trickle(sock: socket.socket, data: bytes, pause: float, limit: float) -> tuple[bytes, float]:
    """Send ``data`` a byte every ``pause`` s until the server answers or closes: (answer, seconds)."""
    sock.settimeout(pause)
    t0 = time.monotonic()
    for byte in data:
        with contextlib.suppress(OSError):
            sock.sendall(bytes([byte]))
        with contextlib.suppress(TimeoutError):
            answer = sock.recv(65536)
            if answer or time.monotonic() - t0 > limit:
                return answer, time.monotonic() - t0
    return b"", time.monotonic() - t0


def test_a_slow_head_is_closed_within_the_bound_and_others_are_served() -> None:
    with _serve() as port:
        slow = socket.create_connection(("127.0.0.1", port))
        idle = socket.create_connection(("127.0.0.1", port))  # connects and sends nothing
        try:
            answer, seconds = _trickle(slow, b"GET /healthz HTTP/1.1\r\nHost: x\r\nX-Slow: " + b"x" * 100, 0.1, 5)
            assert answer.startswith(b"HTTP/1.1 408"), answer
            assert json.loads(answer.split(b"\r\n\r\n", 1)[1])["type"] == "RequestTimeout"
            assert seconds < BOUND + 1.0, seconds
            assert httpx.get(f"http://127.0.0.1:{port}/healthz", timeout=5).status_code == 200
            idle.settimeout(BOUND + 1.0)
            assert idle.recv(65536).startswith(b"HTTP/1.1 408")
            assert idle.recv(65536) == b""  # and closed
        finally:
            slow.close()
            idle.close()


def test_the_bound_covers_the_head_only() -> None:
    """A head sent at once and a body trickled over twice the bound: answered as usual, not cut."""
    data = json.dumps(request_body("fake_hand", n=64)).encode()
    head = b"POST /v1/jobs HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\n"
    with _serve() as port, socket.create_connection(("127.0.0.1", port)) as sock:
        t0 = time.monotonic()
        sock.sendall(head + b"Content-Length: %d\r\n\r\n" % len(data) + data[:-20])
        answer, _ = _trickle(sock, data[-20:], 2 * BOUND / 20, 10)
        if not answer:
            sock.settimeout(5)
            answer = sock.recv(65536)
        assert answer.startswith(b"HTTP/1.1 202"), answer
        assert time.monotonic() - t0 > BOUND
