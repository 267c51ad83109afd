"""`mani serve` serves gRPC beside HTTP in its one process (default on), `--no-grpc` turns it off."""

from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import grpc
import httpx
import pytest
from grpc_health.v1 import health_pb2, health_pb2_grpc

from manifoundation.server.api.cli import settings_from
from manifoundation.server.api.grpc.server import SERVICE_NAME

from ..server import free_port

ROOT = Path(__file__).resolve().parents[3]


def _serve(*flags: str, grpc_port: int | None = None) -> tuple[subprocess.Popen[bytes], int]:
    port = free_port()
    env = dict(os.environ, MANI_PIPELINE="research.staged_pipeline:StagedPipeline", MANI_LOG_LEVEL="WARNING")
    env.pop("MANI_REDIS_URL", None)
    ports = ["--grpc-port", str(grpc_port)] if grpc_port else []
    cmd = [
        sys.executable,
        "-m",
        "manifoundation.cli.main",
        "serve",
        "--port",
        str(port),
        "--workers",
        "1",
        *ports,
        *flags,
    ]
    proc = subprocess.Popen(cmd, cwd=ROOT, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    end = time.monotonic() + 60
    while True:
        assert proc.poll() is None, proc.stderr.read().decode() if proc.stderr else ""
        try:
            if httpx.get(f"http://127.0.0.1:{port}/readyz", timeout=1).status_code == 200:
                return proc, port
        except httpx.HTTPError:
            pass
        assert time.monotonic() < end, "mani serve did not become ready"
        time.sleep(0.1)


def _stop(proc: subprocess.Popen[bytes]) -> None:
    """SIGTERM: a clean exit (uvicorn re-raises the signal it caught), no traceback."""
    proc.send_signal(signal.SIGTERM)
    _, stderr = proc.communicate(timeout=30)
    assert proc.returncode in (0, -signal.SIGTERM), stderr.decode()[-3000:]
    assert b"Traceback" not in stderr, stderr.decode()[-3000:]


def test_the_flags(monkeypatch: pytest.MonkeyPatch) -> None:
    import argparse

    monkeypatch.delenv("MANI_GRPC_PORT", raising=False)  # the suite's conftest turns gRPC off for spawned servers
    parser = argparse.ArgumentParser()
    from manifoundation.server.api.cli import register

    register(parser.add_subparsers())
    assert settings_from(parser.parse_args(["serve"])).grpc_port == 50051
    assert settings_from(parser.parse_args(["serve", "--grpc-port", "6000"])).grpc_port == 6000
    assert settings_from(parser.parse_args(["serve", "--no-grpc"])).grpc_port == 0


def test_mani_serve_serves_grpc_and_stops_cleanly() -> None:
    grpc_port = free_port()
    proc, _ = _serve(grpc_port=grpc_port)
    try:
        with grpc.insecure_channel(f"127.0.0.1:{grpc_port}") as channel:
            health = health_pb2_grpc.HealthStub(channel)
            reply = health.Check(health_pb2.HealthCheckRequest(service=SERVICE_NAME), timeout=5)
            assert reply.status == health_pb2.HealthCheckResponse.SERVING
    finally:
        _stop(proc)


def test_no_grpc_serves_http_only() -> None:
    grpc_port = free_port()
    proc, _ = _serve("--no-grpc")
    try:
        with grpc.insecure_channel(f"127.0.0.1:{grpc_port}") as channel:
            try:
                grpc.channel_ready_future(channel).result(timeout=0.5)
                raise AssertionError("something listens on the gRPC port")
            except grpc.FutureTimeoutError:
                pass
    finally:
        _stop(proc)


def test_a_busy_grpc_port_is_a_clear_error() -> None:
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        env = dict(os.environ, MANI_PIPELINE="research.staged_pipeline:StagedPipeline", MANI_LOG_LEVEL="WARNING")
        cmd = [sys.executable, "-m", "manifoundation.cli.main", "serve", "--port", str(free_port()), "--workers", "1",
               "--grpc-port", str(port)]  # fmt: skip
        done = subprocess.run(cmd, cwd=ROOT, env=env, capture_output=True, text=True, timeout=60)
    assert done.returncode != 0
    assert f"cannot listen on 127.0.0.1:{port}" in done.stderr, done.stderr[-2000:]
