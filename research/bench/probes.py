"""Probes for `mani-lab bench faults`: many posts at once timed to their status line, slow senders, and a /healthz
prober in a process of its own.

An HTTP client library in the same process as 100 concurrent requests measures mostly itself (connection pools,
request objects, a body it must finish uploading before it reads the answer). These probes open their
connections first, then send every request at the same moment and time each one from its first byte sent to
the answer's status line; a body is streamed while the answer is awaited, and sending stops once it has come.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from pathlib import Path


def _head(path: str, size: int, expect: bool) -> bytes:
    extra = "Expect: 100-continue\r\n" if expect else ""
    return (
        f"POST {path} HTTP/1.1\r\nHost: bench\r\nContent-Type: application/json\r\nContent-Length: {size}\r\n"
        f"{extra}\r\n"
    ).encode()


async def _status(reader: asyncio.StreamReader) -> int:
    """The next answer's status (its head read up to the blank line)."""
    parts = (await reader.readline()).split()
    while (await reader.readline()).strip():
        pass
    return int(parts[1]) if len(parts) > 1 and parts[1].isdigit() else 0


async def raw_posts(
    host: str, port: int, path: str, body: bytes, count: int, timeout: float = 60.0, *, expect: bool = False
) -> list[tuple[int, float]]:
    """``count`` posts of ``body`` at once, each on its own connection: ``(status, seconds)`` each (status 0: no
    answer within ``timeout`` or the connection failed). ``expect``: send ``Expect: 100-continue`` and the body
    only after a 100 Continue, else push the body at once while waiting for the answer."""
    streams = [await asyncio.open_connection(host, port) for _ in range(count)]
    go = asyncio.Event()

    async def one(reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> tuple[int, float]:
        async def send() -> None:
            view = memoryview(body)
            for start in range(0, len(view), 1 << 18):
                writer.write(view[start : start + (1 << 18)])
                await writer.drain()

        async def answer() -> int:
            status = await _status(reader)
            if status == 100:
                sender.append(asyncio.ensure_future(send()))
                status = await _status(reader)
            return status

        await go.wait()
        t0 = time.perf_counter()
        writer.write(_head(path, len(body), expect))
        sender = [] if expect else [asyncio.ensure_future(send())]
        try:
            status = await asyncio.wait_for(answer(), timeout)
        except (TimeoutError, OSError, ValueError):
            status = 0
        elapsed = time.perf_counter() - t0
        for task in sender:
            task.cancel()
            with contextlib.suppress(BaseException):
                await task
        writer.transport.abort()
        return status, elapsed

    tasks = [asyncio.ensure_future(one(r, w)) for r, w in streams]
    go.set()
    return list(await asyncio.gather(*tasks))


async def slow_headers(host: str, port: int, count: int, interval: float, duration: float) -> tuple[int, list[float]]:
    """``count`` connections sending a request's headers one byte every ``interval`` s, for ``duration`` s at
    most: how many the server closed, and after how long each."""
    head = b"GET /healthz HTTP/1.1\r\nHost: bench\r\nX-Slow: " + b"x" * 10_000
    loop = asyncio.get_running_loop()
    end = loop.time() + duration

    async def one() -> float | None:
        reader, writer = await asyncio.open_connection(host, port)
        t0 = loop.time()
        try:
            for byte in head:
                writer.write(bytes([byte]))
                await writer.drain()
                with contextlib.suppress(TimeoutError):
                    async with asyncio.timeout_at(min(end, loop.time() + interval)):
                        if not await reader.read(65536):
                            return loop.time() - t0  # EOF: the server closed it
                        return loop.time() - t0  # an answer (408) and then, as it says, the close
                if loop.time() >= end:
                    return None
        except OSError:
            return loop.time() - t0
        finally:
            writer.transport.abort()
        return None

    closed = [t for t in await asyncio.gather(*(one() for _ in range(count))) if t is not None]
    return len(closed), closed


@contextlib.contextmanager
def health_probe(url: str, interval: float = 0.02) -> Iterator[list[float]]:
    """``GET url`` every ``interval`` s from a process of its own (so that the load this process makes does not
    delay the probe) while the block runs; the list it yields is filled with the latencies, s, at its end."""
    root = str(Path(__file__).resolve().parents[2])  # this code, whatever the service under test runs
    code = f"import sys; sys.path.insert(0, {root!r}); from research.bench.probes import _probe; _probe(*sys.argv[1:])"
    proc = subprocess.Popen([sys.executable, "-c", code, url, str(interval)], stdin=subprocess.PIPE,
                            stdout=subprocess.PIPE)  # fmt: skip
    latencies: list[float] = []
    try:
        yield latencies
    finally:
        out, _ = proc.communicate(b"", timeout=60)
        latencies.extend(json.loads(out or b"[]"))


def _probe(url: str, interval: str) -> None:
    """The probe process: poll every ``interval`` s until stdin closes, then print the latencies as JSON."""
    import httpx

    stop = threading.Event()

    def wait_for_eof() -> None:
        sys.stdin.read()
        stop.set()

    threading.Thread(target=wait_for_eof, daemon=True).start()
    latencies = []
    with httpx.Client(timeout=60) as http:
        while not stop.is_set():
            t0 = time.perf_counter()
            with contextlib.suppress(httpx.HTTPError):
                if http.get(url).status_code == 200:
                    latencies.append(time.perf_counter() - t0)
            stop.wait(float(interval))
    print(json.dumps(latencies))
