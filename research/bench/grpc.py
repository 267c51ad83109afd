"""`mani-lab bench grpc`: the same synthesis requests over gRPC and over HTTP + msgpack, side by side, one service.

Starts `mani serve` (embedded workers, gRPC beside HTTP in its one process) unless ``--url``/``--grpc`` name a
running one, then, for each concurrency level and each transport in turn, C clients send the same small request
back to back (`Synthesize` / `POST /v1/synthesize`). Reports p50/p99 latency, requests/s and the added latency
(end to end minus the worker's compute, from the result's stage timings) per transport.
"""

from __future__ import annotations

import argparse
import asyncio
import json
import statistics
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

from research.bench.service import _pct

EXAMPLE = """examples:
  python -m research.bench.grpc --pipeline research.staged_pipeline:StagedPipeline --pipeline-options '{"stage_seconds":
  0.01}'
  python -m research.bench.grpc --clients 1,8 --requests 100 --json artifacts/bench_grpc.json"""


def register(subparsers: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Add ``grpc`` to the ``mani-lab bench`` sub-commands."""
    parser = subparsers.add_parser(
        "grpc",
        help="gRPC vs HTTP+msgpack latency on one service",
        description=(__doc__ or "").splitlines()[0],
        epilog=EXAMPLE,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    arguments(parser)


def arguments(parser: argparse.ArgumentParser) -> None:
    """The benchmark's options."""
    parser.add_argument("--url", help="HTTP base URL of a running service (with --grpc)")
    parser.add_argument("--grpc", help="host:port of its gRPC server")
    parser.add_argument("--clients", default="1,8", help="concurrency levels, comma-separated (1,8)")
    parser.add_argument("--requests", type=int, default=0, help="requests per level and transport (max(40, 8×C))")
    parser.add_argument("--workers", type=int, default=2, help="embedded workers of the started service (2)")
    parser.add_argument("--points", type=int, default=256, help="object points per request (256)")
    parser.add_argument("--hand", default="test_gripper", help="hand name (test_gripper: the staged pipeline's)")
    parser.add_argument(
        "--pipeline", default="research.staged_pipeline:StagedPipeline", help="worker pipeline (MANI_PIPELINE)"
    )
    parser.add_argument("--pipeline-options", metavar="JSON", default='{"stage_seconds": 0.005}')
    parser.add_argument("--json", type=Path, help="also write the figures to this JSON file")
    parser.set_defaults(func=run)


def _summary(transport: str, clients: int, wall: float, latencies: list[float], added: list[float]) -> dict[str, Any]:
    ok = len(latencies)
    return {
        "transport": transport,
        "clients": clients,
        "ok": ok,
        "req_per_s": round(ok / wall, 1),
        "p50_ms": round(_pct(latencies, 0.5) * 1000, 2),
        "p99_ms": round(_pct(latencies, 0.99) * 1000, 2),
        "added_ms_p50": round(statistics.median(added) * 1000, 2),
    }


async def _clients(clients: int, total: int, one: Any) -> tuple[float, list[float], list[float]]:
    """Run ``one()`` (returns the worker's compute seconds) ``total`` times from ``clients`` loops."""
    latencies: list[float] = []
    added: list[float] = []
    remaining = total

    async def loop() -> None:
        nonlocal remaining
        while remaining > 0:
            remaining -= 1
            t0 = time.perf_counter()
            compute = await one()
            elapsed = time.perf_counter() - t0
            latencies.append(elapsed)
            added.append(elapsed - compute)

    start = time.perf_counter()
    await asyncio.gather(*(loop() for _ in range(clients)))
    return time.perf_counter() - start, latencies, added


async def _http(url: str, body: bytes, clients: int, total: int) -> dict[str, Any]:
    import httpx

    from manifoundation.contract.codec import MSGPACK, unpack

    headers = {"Content-Type": MSGPACK, "Accept": MSGPACK}
    limits = httpx.Limits(max_connections=clients, max_keepalive_connections=clients)
    async with httpx.AsyncClient(base_url=url, timeout=120, limits=limits) as http:

        async def one() -> float:
            response = await http.post("/v1/synthesize", content=body, headers=headers)
            response.raise_for_status()
            return float(sum(unpack(response.content)["timings"].values()))

        return _summary("http+msgpack", clients, *await _clients(clients, total, one))


async def _grpc(target: str, message: Any, clients: int, total: int) -> dict[str, Any]:
    import grpc

    from manifoundation.contract.protos.v1 import manifoundation_pb2_grpc as pb_grpc

    async with grpc.aio.insecure_channel(target) as channel:
        stub = pb_grpc.ManiFoundationStub(channel)

        async def one() -> float:
            result = await stub.Synthesize(message, timeout=120)
            return float(sum(result.timings.values()))

        return _summary("grpc", clients, *await _clients(clients, total, one))


def _start(args: argparse.Namespace) -> tuple[subprocess.Popen[bytes], str, str]:
    """`mani-lab bench service`'s fresh service, with gRPC on a free port of its own."""
    from research.bench.service import _free_port, _start_service

    grpc_port = _free_port()
    proc, url = _start_service(args, grpc_port=grpc_port)
    return proc, url, f"127.0.0.1:{grpc_port}"


def run(args: argparse.Namespace) -> int:
    """Run the benchmark; prints one row per level and transport (and writes JSON with ``--json``)."""
    from manifoundation.contract import SynthesisRequest
    from manifoundation.contract.codec import MSGPACK, dump_model
    from manifoundation.contract.protos.convert import to_proto
    from manifoundation.contract.protos.v1 import manifoundation_pb2 as pb
    from research.bench.service import _wait_ready, request_body

    proc = None
    if args.url and args.grpc:
        url, target = args.url, args.grpc
    else:
        proc, url, target = _start(args)
    try:
        _wait_ready(url, proc, args.workers)
        request = SynthesisRequest.model_validate(request_body(args.points, args.hand, "direct_grasp"))
        body, message = dump_model(request, MSGPACK), to_proto(request, pb.SynthesisRequest)
        rows = []
        for clients in [int(c) for c in args.clients.split(",") if c.strip()]:
            total = args.requests or max(40, 8 * clients)
            asyncio.run(_grpc(target, message, clients, min(total, 8)))  # warm both paths up
            asyncio.run(_http(url, body, clients, min(total, 8)))
            for row in (
                asyncio.run(_grpc(target, message, clients, total)),
                asyncio.run(_http(url, body, clients, total)),
            ):
                rows.append(row)
                print(json.dumps(row))
        if args.json:
            args.json.parent.mkdir(parents=True, exist_ok=True)
            args.json.write_text(json.dumps({"points": args.points, "pipeline": args.pipeline, "rows": rows}, indent=2))
    finally:
        if proc is not None:
            proc.terminate()
            proc.wait(timeout=60)
    return 0


if __name__ == "__main__":
    main_parser = argparse.ArgumentParser(
        description=(__doc__ or "").splitlines()[0],
        epilog=EXAMPLE,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    arguments(main_parser)
    sys.exit(run(main_parser.parse_args()))
