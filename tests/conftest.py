"""Shared fixtures: a real Redis for the tests that need one, with a key prefix unique to this run.

Redis is found in this order: ``MANI_TEST_REDIS_URL``; a server on 127.0.0.1:6379; a `redis-server` started on
a free port for this session (skipped with a reason when none is installed). Tests only ever touch keys under
their own prefix and delete exactly those at the end.
"""

from __future__ import annotations

import os
import shutil
import socket
import subprocess
import time
import uuid
from collections.abc import Iterator

import pytest
from hypothesis import settings

# `mani serve` listens for gRPC on 50051 by default; the `mani serve` processes tests start (each on a free HTTP
# port) would race for that one port, so they serve HTTP only unless a test asks for gRPC (`--grpc-port`).
os.environ.setdefault("MANI_GRPC_PORT", "0")

# No per-example deadline: the suite shares two cores with servers, workers and other runs, where a 200 ms deadline
# fails a correct example at random (hypothesis's FlakyFailure). Tests that care about time measure it themselves.
settings.register_profile("shared-cores", deadline=None)
settings.load_profile("shared-cores")


def _free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return int(sock.getsockname()[1])


def _answers(url: str) -> bool:
    import redis

    try:
        return bool(redis.Redis.from_url(url, socket_connect_timeout=1).ping())
    except redis.RedisError:
        return False


@pytest.fixture(scope="session")
def redis_url() -> Iterator[str]:
    """URL of a Redis server these tests may use."""
    explicit = os.environ.get("MANI_TEST_REDIS_URL")
    if explicit:
        yield explicit
        return
    local = "redis://127.0.0.1:6379/0"
    if _answers(local):
        yield local
        return
    binary = shutil.which("redis-server")
    if binary is None:
        pytest.skip("no Redis reachable and redis-server is not installed")
    port = _free_port()
    proc = subprocess.Popen(
        [binary, "--port", str(port), "--bind", "127.0.0.1", "--save", "", "--appendonly", "no"],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    url = f"redis://127.0.0.1:{port}/0"
    deadline = time.monotonic() + 10
    while not _answers(url):
        if time.monotonic() > deadline:
            proc.kill()
            pytest.fail("redis-server did not start")
        time.sleep(0.05)
    yield url
    proc.terminate()
    proc.wait(timeout=10)


@pytest.fixture
def redis_prefix(redis_url: str) -> Iterator[str]:
    """A key prefix unique to one test; its keys are deleted afterwards (and no others)."""
    import redis

    prefix = f"mani-test:{uuid.uuid4().hex[:12]}:"
    yield prefix
    client = redis.Redis.from_url(redis_url)
    keys = list(client.scan_iter(match=prefix + "*", count=1000))
    if keys:
        client.delete(*keys)
    client.close()
