"""`mani-lab bench service`: a bounded load on the HTTP service from a second process, over loopback.

Starts `mani serve` (embedded workers) as a child process unless ``--url`` names a running service, then, for
each concurrency level, C clients each send small `POST /v1/synthesize` requests back to back. Reports p50/p99
latency and requests/s per level, the service overhead (end-to-end time ÷ the worker's compute time, from the
result's stage timings) and the API process's resident memory (its worker processes are not counted).
"""

from __future__ import annotations

import argparse
import asyncio
import json
import os
import socket
import statistics
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

from research.bench.rss import HEADER, format_row, rss_mb, rss_over_requests

EXAMPLE = """examples:
  mani-lab bench service                              # 1, 8, 32 clients against a fresh `mani serve --workers 2`
  mani-lab bench service --clients 1,8 --requests 40 --json artifacts/bench_service.json
  mani-lab bench service --url http://127.0.0.1:8000  # an already running service
  mani-lab bench service --pipeline research.staged_pipeline:StagedPipeline --pipeline-options '{"stage_seconds": 0.01}'
                                                  # the service and queue alone, with a known compute time
  mani-lab bench service --clients 1 --rss 10000 --pipeline research.staged_pipeline:StagedPipeline
                                                  # API and worker RSS over 10 000 requests"""


def register(subparsers: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Add ``service`` to the ``mani-lab bench`` sub-commands."""
    parser = subparsers.add_parser(
        "service",
        help="load-test the HTTP service (latency, req/s, overhead, API memory)",
        description=(__doc__ or "").splitlines()[0],
        epilog=EXAMPLE,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("--url", help="benchmark this running service instead of starting one")
    parser.add_argument("--clients", default="1,8,32", help="concurrency levels, comma-separated (1,8,32)")
    parser.add_argument("--requests", type=int, default=0, help="requests per level (default: max(24, 4×C))")
    parser.add_argument("--workers", type=int, default=2, help="embedded workers of the started service (2)")
    parser.add_argument("--points", type=int, default=256, help="object points per request (256)")
    parser.add_argument("--hand", help="hand name (default: the first one the service lists)")
    parser.add_argument("--method", default="direct_grasp", help="options.method of the requests")
    parser.add_argument("--pipeline", help="worker pipeline 'module:attr' of the started service (MANI_PIPELINE)")
    parser.add_argument("--pipeline-options", metavar="JSON", help="its keyword arguments (MANI_PIPELINE_OPTIONS)")
    parser.add_argument("--key", help="API key of a service with auth on")
    parser.add_argument(
        "--rss",
        type=int,
        default=0,
        metavar="N",
        help="then N more requests, with API and worker RSS every N/10 (`research.bench.rss`)",
    )
    parser.add_argument("--rss-clients", type=int, default=8, help="clients of the --rss run (8)")
    parser.add_argument("--json", type=Path, help="also write the figures to this JSON file")
    parser.set_defaults(func=run)


def _free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return int(sock.getsockname()[1])


def request_body(points: int, hand: str, method: str, seed: int = 0) -> dict[str, Any]:
    """A small force-closure request on a sphere of radius 4 cm (Fibonacci lattice, outward normals)."""
    import numpy as np

    i = np.arange(points) + 0.5
    phi = np.arccos(1 - 2 * i / points)
    theta = np.pi * (1 + 5**0.5) * i
    normals = np.stack([np.cos(theta) * np.sin(phi), np.sin(theta) * np.sin(phi), np.cos(phi)], axis=1)
    return {
        "object": {
            "points": (normals * 0.04).round(6).tolist(),
            "normals": normals.round(6).tolist(),
            "properties": {"friction": 0.8, "density": 500},
        },
        "task": {"kind": "force_closure"},
        "robot": {"name": hand},
        "options": {"method": method, "seed": seed, "timeout": 120, "max_iterations": 50},
    }


def _compute_seconds(result: dict[str, Any]) -> float | None:
    timings = result.get("timings") or {}
    if "total" in timings:
        return float(timings["total"])
    values = [float(v) for v in timings.values()]
    return sum(values) if values else None


def _pct(values: list[float], q: float) -> float:
    ordered = sorted(values)
    pos = (len(ordered) - 1) * q
    low = int(pos)
    high = min(low + 1, len(ordered) - 1)
    return ordered[low] + (ordered[high] - ordered[low]) * (pos - low)


async def _level(url: str, headers: dict[str, str], body: bytes, clients: int, total: int) -> dict[str, Any]:
    import httpx

    latencies: list[float] = []
    ratios: list[float] = []
    overheads: list[float] = []
    statuses: dict[int, int] = {}
    remaining = total

    async def client(http: httpx.AsyncClient) -> None:
        nonlocal remaining
        while remaining > 0:
            remaining -= 1
            t0 = time.perf_counter()
            response = await http.post(f"{url}/v1/synthesize", content=body, headers=headers)
            elapsed = time.perf_counter() - t0
            statuses[response.status_code] = statuses.get(response.status_code, 0) + 1
            if response.status_code == 200:
                latencies.append(elapsed)
                compute = _compute_seconds(response.json())
                if compute:
                    ratios.append(elapsed / compute)
                    overheads.append(elapsed - compute)

    limits = httpx.Limits(max_connections=clients, max_keepalive_connections=clients)
    async with httpx.AsyncClient(timeout=300, limits=limits) as http:
        start = time.perf_counter()
        await asyncio.gather(*(client(http) for _ in range(clients)))
        wall = time.perf_counter() - start
    ok = len(latencies)
    return {
        "clients": clients,
        "requests": total,
        "ok": ok,
        "statuses": {str(k): v for k, v in sorted(statuses.items())},
        "wall_s": round(wall, 3),
        "req_per_s": round(ok / wall, 2) if wall > 0 else 0.0,
        "p50_ms": round(_pct(latencies, 0.5) * 1000, 1) if ok else None,
        "p99_ms": round(_pct(latencies, 0.99) * 1000, 1) if ok else None,
        "overhead_ratio_p50": round(statistics.median(ratios), 3) if ratios else None,
        "overhead_ms_p50": round(statistics.median(overheads) * 1000, 1) if overheads else None,
    }


def _start_service(args: argparse.Namespace, grpc_port: int | None = None) -> tuple[subprocess.Popen[bytes], str]:
    """A fresh `mani serve` on free loopback ports: HTTP only, or also gRPC on ``grpc_port``."""
    port = _free_port()
    env = dict(os.environ, MANI_RATE_LIMIT_PER_S="0", MANI_LOG_LEVEL="WARNING")
    env.pop("MANI_REDIS_URL", None)
    if args.pipeline:
        env["MANI_PIPELINE"] = args.pipeline
    if args.pipeline_options:
        env["MANI_PIPELINE_OPTIONS"] = args.pipeline_options
    cmd = [
        sys.executable,
        "-m",
        "manifoundation.cli.main",
        "serve",
        "--host",
        "127.0.0.1",
        "--port",
        str(port),
        "--workers",
        str(args.workers),
        *(["--grpc-port", str(grpc_port)] if grpc_port else ["--no-grpc"]),  # no race for the default gRPC port
    ]
    proc = subprocess.Popen(cmd, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return proc, f"http://127.0.0.1:{port}"


def _wait_ready(url: str, proc: subprocess.Popen[bytes] | None, workers: int, timeout: float = 300) -> None:
    """Until ``workers`` workers are live (``/readyz`` counts them; "ready" also needs trained weights, which
    the direct-grasp requests of this benchmark do not use)."""
    import httpx

    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if proc is not None and proc.poll() is not None:
            raise RuntimeError(f"the service exited with code {proc.returncode}")
        try:
            response = httpx.get(f"{url}/readyz", timeout=2)
            if response.status_code == 200 or response.json().get("workers", 0) >= workers:
                return
        except (httpx.HTTPError, ValueError):
            pass
        time.sleep(0.5)
    raise RuntimeError(f"{url}: fewer than {workers} live workers after {timeout:.0f} s")


def run(args: argparse.Namespace) -> int:
    """Run the benchmark; prints a table (and writes JSON with ``--json``)."""
    import httpx

    levels = [int(c) for c in args.clients.split(",") if c.strip()]
    proc, url = (None, args.url.rstrip("/")) if args.url else _start_service(args)
    try:
        _wait_ready(url, proc, args.workers if proc is not None else 1)
        headers = {"Content-Type": "application/json"}
        if args.key:
            headers["Authorization"] = f"Bearer {args.key}"
        hand = args.hand or httpx.get(f"{url}/v1/robots", headers=headers).json()["robots"][0]["name"]
        body = json.dumps(request_body(args.points, hand, args.method)).encode()
        asyncio.run(_level(url, headers, body, 1, 3))  # warm-up (connections, first job of each worker)
        rows = []
        for clients in levels:
            total = args.requests or max(24, 4 * clients)
            row = asyncio.run(_level(url, headers, body, clients, total))
            if proc is not None:
                row["api_rss_mb"] = round(rss_mb(proc.pid).get("VmRSS", 0.0), 1)
            rows.append(row)
            print(_format(row), flush=True)
        if args.rss and proc is not None:
            print(HEADER, flush=True)
            table = asyncio.run(
                rss_over_requests(url, headers, body, proc.pid, args.rss, args.rss_clients, on_row=_print_row)
            )
            rows.append({"rss": table})
        figures = {
            "url": url,
            "hand": hand,
            "points": args.points,
            "method": args.method,
            "workers": args.workers,
            "cpus": os.cpu_count(),
            "levels": rows,
            "api_rss_mb": rss_mb(proc.pid) if proc is not None else None,
        }
        print(json.dumps({"api_rss_mb": figures["api_rss_mb"], "hand": hand, "points": args.points}))
        if args.json:
            args.json.parent.mkdir(parents=True, exist_ok=True)
            args.json.write_text(json.dumps(figures, indent=2))
        return 0 if all(r.get("ok", True) for r in rows) else 1
    finally:
        if proc is not None:
            proc.terminate()
            try:
                proc.wait(timeout=30)
            except subprocess.TimeoutExpired:
                proc.kill()


def _print_row(row: dict[str, Any]) -> None:
    print(format_row(row), flush=True)


def _format(row: dict[str, Any]) -> str:
    return (
        f"clients={row['clients']:>3}  ok={row['ok']}/{row['requests']}  {row['req_per_s']:>7} req/s  "
        f"p50={row['p50_ms']} ms  p99={row['p99_ms']} ms  overhead×={row['overhead_ratio_p50']}  "
        f"(+{row['overhead_ms_p50']} ms)  api_rss={row.get('api_rss_mb')} MB  statuses={row['statuses']}"
    )
