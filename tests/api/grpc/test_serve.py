"""`mani serve` serves gRPC beside HTTP in its one process (default on), `--no-grpc` turns it off; busy ports are
found before anything loads (a port the user set: one line and exit 2; a default one, HTTP 8000 or gRPC 50051: a
free port instead, printed)."""

from __future__ import annotations

import contextlib
import errno
import os
import signal
import socket
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import grpc
import httpx
import pytest
from grpc_health.v1 import health_pb2, health_pb2_grpc

from manifoundation.server.api.cli import settings_from
from manifoundation.server.api.grpc.server import SERVICE_NAME
from manifoundation.server.api.settings import Settings

from ..server import free_port

ROOT = Path(__file__).resolve().parents[3]


def _env(**extra: str | None) -> dict[str, str]:
    """The environment of a `mani serve` under test (fast staged pipeline, embedded queue); None removes a name."""
    env = dict(os.environ, MANI_PIPELINE="research.staged_pipeline:StagedPipeline", MANI_LOG_LEVEL="WARNING")
    env.pop("MANI_REDIS_URL", None)
    for name, value in extra.items():
        if value is None:
            env.pop(name, None)
        else:
            env[name] = value
    return env


def _serve(
    *flags: str, grpc_port: int | None = None, env: dict[str, str] | None = None
) -> tuple[subprocess.Popen[bytes], int]:
    port = free_port()
    env = env if env is not None else _env()
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
    _until_ready(proc, port)
    return proc, port


def _until_ready(proc: subprocess.Popen[bytes], port: int) -> None:
    """Wait (≤ 60 s) until the `mani serve` in ``proc`` answers /readyz on ``port``."""
    end = time.monotonic() + 60
    while True:
        assert proc.poll() is None, proc.stderr.read().decode() if proc.stderr else ""
        try:
            if httpx.get(f"http://127.0.0.1:{port}/readyz", timeout=1).status_code == 200:
                return
        except httpx.HTTPError:
            pass
        assert time.monotonic() < end, "mani serve did not become ready"
        time.sleep(0.1)


@contextlib.contextmanager
def _busy(port: int) -> Iterator[None]:
    """``port`` on 127.0.0.1 held as another program would hold it (or found held already: just as busy)."""
    holder = socket.socket()
    try:
        try:
            holder.bind(("127.0.0.1", port))
            holder.listen()
        except OSError as exc:
            assert exc.errno == errno.EADDRINUSE, exc
        yield
    finally:
        holder.close()


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
    proc, _ = _serve("--no-grpc", env=_env(MANI_GRPC_PORT=str(grpc_port)))  # the flag beats the environment
    try:
        with grpc.insecure_channel(f"127.0.0.1:{grpc_port}") as channel:
            try:
                grpc.channel_ready_future(channel).result(timeout=0.5)
                raise AssertionError("something listens on the gRPC port")
            except grpc.FutureTimeoutError:
                pass
    finally:
        _stop(proc)


def _held() -> socket.socket:
    """A socket listening on a free port of 127.0.0.1, as another program would hold it."""
    sock = socket.socket()
    sock.bind(("127.0.0.1", 0))
    sock.listen()
    return sock


def _refused(*flags: str, env: dict[str, str]) -> tuple[subprocess.CompletedProcess[str], float]:
    cmd = [sys.executable, "-m", "manifoundation.cli.main", "serve", "--workers", "1", *flags]
    start = time.monotonic()
    done = subprocess.run(cmd, cwd=ROOT, env=env, capture_output=True, text=True, timeout=60)
    return done, time.monotonic() - start


# Under a second on an idle machine (Python's start and the settings); the bound leaves room for a loaded one and
# is still far below the model loading (~40 s) that a busy port used to cost.
FAST_S = 5.0


def test_a_busy_http_port_fails_at_once_with_one_line() -> None:
    with _held() as taken:
        port = taken.getsockname()[1]
        done, seconds = _refused("--port", str(port), env=_env())
    assert done.returncode == 2 and seconds < FAST_S, (seconds, done.stderr[-2000:])
    line = done.stderr.strip()
    assert "\n" not in line and f"127.0.0.1:{port}" in line and "--port" in line and "PORT" in line, line


def test_a_busy_grpc_port_that_was_set_fails_at_once_with_one_line() -> None:
    with _held() as taken:
        port = taken.getsockname()[1]
        done, seconds = _refused("--port", str(free_port()), "--grpc-port", str(port), env=_env())
        by_env, _ = _refused("--port", str(free_port()), env=_env(MANI_GRPC_PORT=str(port)))
    assert done.returncode == 2 and seconds < FAST_S, (seconds, done.stderr[-2000:])
    line = done.stderr.strip()
    assert "\n" not in line and f"cannot listen for gRPC on 127.0.0.1:{port}" in line, line
    assert all(word in line for word in ("--grpc-port", "GRPC_PORT", "--no-grpc")), line
    assert by_env.returncode == 2 and by_env.stderr.strip() == line


def test_a_busy_default_grpc_port_is_replaced_by_a_free_one() -> None:
    default = Settings.model_fields["grpc_port"].default
    with _busy(default):
        proc, _ = _serve(env=_env(MANI_GRPC_PORT=None))  # neither flag nor environment: the default
        try:
            assert proc.stderr is not None
            line = proc.stderr.readline().decode()
            assert f"gRPC port {default} is taken" in line and "GRPC_PORT" in line, line
            moved = int(line.split("gRPC listens on 127.0.0.1:")[1].split()[0])
            assert moved != default
            with grpc.insecure_channel(f"127.0.0.1:{moved}") as channel:
                health = health_pb2_grpc.HealthStub(channel)
                reply = health.Check(health_pb2.HealthCheckRequest(service=SERVICE_NAME), timeout=5)
                assert reply.status == health_pb2.HealthCheckResponse.SERVING
        finally:
            _stop(proc)


def test_a_busy_default_http_port_is_replaced_by_a_free_one() -> None:
    """The README's first command on a busy machine: 8000 taken, no port asked for → a free port, printed."""
    default = Settings.model_fields["port"].default
    with _busy(default):
        cmd = [sys.executable, "-m", "manifoundation.cli.main", "serve", "--workers", "1", "--no-grpc"]
        proc = subprocess.Popen(cmd, cwd=ROOT, env=_env(MANI_PORT=None), stdout=subprocess.DEVNULL,
                                stderr=subprocess.PIPE)  # fmt: skip
        try:
            assert proc.stderr is not None
            line = proc.stderr.readline().decode()
            assert f"port {default} is taken" in line and "--port" in line and "MANI_URL" in line, line
            moved = int(line.split("listens on http://127.0.0.1:")[1].split()[0])
            assert moved != default
            _until_ready(proc, moved)  # ready on the port it printed
        finally:
            _stop(proc)
