"""Every script in ``examples/`` as shipped, against a real `mani serve` (its own models and weights, embedded
workers) on free ports: each exits 0. A user's first run is these scripts; they default to the service's best
method (``auto``), and this test is what keeps them working.

Slow (``-m slow``): the models load (~40 s) and ``batch_100.py`` runs 100 syntheses.
"""

from __future__ import annotations

import os
import shutil
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import httpx
import pytest

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ROOT / "examples"
SCRIPTS = sorted(p.name for p in EXAMPLES.glob("*.py"))
# What a script is given beyond MANI_URL, as examples/README.md runs it ("URL": the service's base URL).
ARGS: dict[str, list[str]] = {"planner_waypoints.py": ["--url", "URL"]}  # local by default; --url: the service
SCRIPT_TIMEOUT_S = 900


def _free_port() -> int:
    import socket

    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return int(sock.getsockname()[1])


@pytest.fixture(scope="module")
def service(tmp_path_factory: pytest.TempPathFactory) -> Iterator[str]:
    """`mani serve` as `make serve` runs it (the shipped pipeline and weights), on a free HTTP and gRPC port; its
    log goes to a file (a pipe nobody reads would fill and stall the service)."""
    log = tmp_path_factory.mktemp("serve") / "serve.log"
    port = _free_port()
    env = {k: v for k, v in os.environ.items() if not k.startswith("MANI_")}  # the shipped defaults, nothing else
    cmd = [sys.executable, "-m", "manifoundation.cli.main", "serve", "--port", str(port),
           "--grpc-port", str(_free_port())]  # fmt: skip
    with log.open("w") as out:
        proc = subprocess.Popen(cmd, cwd=ROOT, env=env, stdout=subprocess.DEVNULL, stderr=out)
    url = f"http://127.0.0.1:{port}"
    try:
        end = time.monotonic() + 600
        while True:
            assert proc.poll() is None, log.read_text()[-3000:]
            assert time.monotonic() < end, "mani serve did not become ready"
            try:
                if httpx.get(f"{url}/readyz", timeout=2).status_code == 200:
                    break
            except httpx.HTTPError:
                pass
            time.sleep(0.5)
        yield url
    finally:
        proc.send_signal(signal.SIGTERM)
        try:
            proc.wait(timeout=60)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()


def test_every_example_is_covered() -> None:
    assert "sync_call.py" in SCRIPTS and "batch_100.py" in SCRIPTS, SCRIPTS
    assert set(ARGS) <= set(SCRIPTS), "ARGS names a script that is gone"


@pytest.mark.slow
@pytest.mark.timeout(1800)
@pytest.mark.parametrize("script", SCRIPTS)
def test_the_example_runs_as_shipped(script: str, service: str, tmp_path: Path) -> None:
    path = EXAMPLES / script
    if script == "make_data.py":  # it rewrites examples/data/ beside itself: run a copy, writing the copy's data/
        shutil.copy(path, tmp_path / script)
        path = tmp_path / script
    argv = [service if a == "URL" else a for a in ARGS.get(script, [])]
    env = {k: v for k, v in os.environ.items() if not k.startswith("MANI_")}
    env["MANI_URL"] = service
    start = time.monotonic()
    done = subprocess.run([sys.executable, str(path), *argv], cwd=tmp_path, env=env, capture_output=True, text=True,
                          timeout=SCRIPT_TIMEOUT_S)  # fmt: skip
    seconds = time.monotonic() - start
    print(f"{script}: exit {done.returncode} in {seconds:.1f} s\n{done.stdout[-1500:]}")
    assert done.returncode == 0, f"{script} exited {done.returncode}:\n{done.stdout[-3000:]}\n{done.stderr[-3000:]}"
