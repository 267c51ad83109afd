"""`mani-lab bench service --rss N`: resident memory of the API process and of each worker over N requests.

C clients send `POST /v1/synthesize` back to back (the benchmark's request) until N have been answered; every
N / rows requests the API process's RSS and that of each embedded worker process (its children running
`manifoundation.server.worker.child`) are read from /proc. The answer to "does it grow?" is the table: the last rows
against the first rows after warm-up, not one figure at the end.

Each worker's anonymous memory (its heap, Python objects, tensors, compiled code: what a leak grows) is shown
beside its RSS. RSS also counts the pages of the shared libraries it maps, and how many of those are resident
depends on the page cache, not on the worker: right after `pip install` wrote them, the same worker read 667 MB
at start, and 549 MB once those files' cached pages were dropped and read back from disk (`libllvmlite.so` alone
116 against 41 MB).
"""

from __future__ import annotations

import asyncio
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

HEADER = "| requests | s | failed | API RSS MB | worker RSS MB | worker anonymous MB |\n|---:|---:|---:|---:|---|---|"


def rss_mb(pid: int, fields: tuple[str, ...] = ("VmRSS", "VmHWM")) -> dict[str, float]:
    """Memory of a process from Linux /proc, MB: by default resident (VmRSS) and peak resident (VmHWM); any
    ``fields`` of its status (``RssAnon``: the anonymous part of VmRSS). Empty when the process is gone."""
    out: dict[str, float] = {}
    try:
        for line in Path(f"/proc/{pid}/status").read_text().splitlines():
            name, _, value = line.partition(":")
            if name in fields:
                out[name] = int(value.split()[0]) / 1024
    except OSError:
        pass
    return out


def worker_pids(parent: int) -> list[int]:
    """The embedded worker processes of the API process ``parent`` (Linux /proc), oldest first."""
    found = []
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
            if (
                int(fields[1]) == parent
                and b"manifoundation.server.worker.child" in (stat.parent / "cmdline").read_bytes()
            ):
                found.append(int(stat.parent.name))
        except (OSError, ValueError, IndexError):
            continue
    return sorted(found)


def sample(api_pid: int) -> dict[str, Any]:
    """RSS of the API process and of each of its workers, and the workers' anonymous memory, MB."""
    workers = [rss_mb(p, ("VmRSS", "RssAnon")) for p in worker_pids(api_pid)]
    return {"api_mb": round(rss_mb(api_pid).get("VmRSS", 0.0), 1),
            "workers_mb": [round(w.get("VmRSS", 0.0), 1) for w in workers],
            "workers_anon_mb": [round(w.get("RssAnon", 0.0), 1) for w in workers]}  # fmt: skip


async def rss_over_requests(
    url: str, headers: dict[str, str], body: bytes, api_pid: int, total: int, clients: int, rows: int = 10,
    on_row: Callable[[dict[str, Any]], None] | None = None,
) -> list[dict[str, Any]]:  # fmt: skip
    """Send ``total`` requests with ``clients`` clients; a row (requests answered, seconds, failures so far, RSS)
    at the start and every ``total / rows`` answers, each also handed to ``on_row`` as it is taken."""
    import httpx

    step = max(1, total // rows)
    table: list[dict[str, Any]] = []
    done = sent = failed = 0
    start = time.perf_counter()

    def row() -> None:
        table.append({"requests": done, "seconds": round(time.perf_counter() - start, 1), "failed": failed,
                      **sample(api_pid)})  # fmt: skip
        if on_row is not None:
            on_row(table[-1])

    async def client(http: httpx.AsyncClient) -> None:
        nonlocal done, sent, failed
        while sent < total:
            sent += 1
            answer = await http.post(f"{url}/v1/synthesize", content=body, headers=headers)
            failed += answer.status_code != 200
            done += 1
            if done % step == 0 or done == total:
                row()

    row()
    limits = httpx.Limits(max_connections=clients, max_keepalive_connections=clients)
    async with httpx.AsyncClient(timeout=300, limits=limits) as http:
        await asyncio.gather(*(client(http) for _ in range(clients)))
    return table


def format_row(row: dict[str, Any]) -> str:
    """One row of the Markdown table under `HEADER`."""
    workers = ", ".join(f"{w:.0f}" for w in row["workers_mb"]) or "-"
    anon = ", ".join(f"{w:.0f}" for w in row.get("workers_anon_mb", [])) or "-"
    return f"| {row['requests']} | {row['seconds']} | {row['failed']} | {row['api_mb']:.0f} | {workers} | {anon} |"
