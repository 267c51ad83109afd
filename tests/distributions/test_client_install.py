"""The client wheel alone, in a fresh venv, runs the README's quickstart against a real server (slow: CI runs it
after `make test`, `.ci/run`).

Both distributions are built (wheel + sdist: `python -m build`); the client wheel is installed into an empty venv
(its dependencies from the package index or the local wheel cache), which must stay torch-free and small. Then,
against `mani serve` started from the full install (the real pipeline and shipped weights), from a folder outside
the repository and without its PYTHONPATH: the quickstart's `mani synthesize` (without the extras: `--view` refused
clearly, before any work), then with ``[view,grpc]`` the README's Python snippet and a `GrpcClient` call. A
``sitecustomize`` on the client's path records every module each client process imported: never torch, never the
server's packages. The figures (install seconds, venv size) are printed for the README.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import sys
import time
import zipfile
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import httpx
import pytest

from manifoundation.contract import SynthesisResult
from tests.api.server import free_port

pytestmark = pytest.mark.slow
ROOT = Path(__file__).resolve().parents[2]
SERVER_PACKAGES = {"torch", "manifoundation.server", "manifoundation.core", "research", "fastapi", "uvicorn"}
MAX_INSTALL_S = 90.0  # goal: well under a minute from the local wheel cache
MAX_VENV_MB = 150.0
PROBE = """import atexit, json, os, sys
def _dump():
    with open(os.environ["MANI_PROBE_OUT"], "a") as out:
        out.write(json.dumps({"argv": sys.argv, "modules": sorted(sys.modules)}) + "\\n")
atexit.register(_dump)
"""


def run(cmd: list[str], *, timeout: float, **kwargs: Any) -> subprocess.CompletedProcess[str]:
    """Run ``cmd``; fail the test with its output unless it exits 0."""
    done = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, **kwargs)
    tail = f"{done.stdout[-3000:]}\n{done.stderr[-3000:]}"
    assert done.returncode == 0, f"{' '.join(map(str, cmd))} → {done.returncode}\n{tail}"
    return done


@pytest.fixture(scope="module")
def wheels(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Both distributions built into one folder. setuptools writes the server's metadata into the checkout
    (``manifoundation.egg-info``), where it would stand for the installed one on ``sys.path``: the checkout gets
    back what it had."""
    out = tmp_path_factory.mktemp("dist")
    egg_info, kept = ROOT / "manifoundation.egg-info", tmp_path_factory.mktemp("kept") / "egg-info"
    if egg_info.exists():
        shutil.copytree(egg_info, kept)
    try:
        for project in (ROOT / "distributions" / "client", ROOT):
            run([sys.executable, "-m", "build", "--outdir", str(out), str(project)], timeout=600)
    finally:
        shutil.rmtree(egg_info, ignore_errors=True)
        if kept.exists():
            shutil.copytree(kept, egg_info)
    return out


@pytest.fixture(scope="module")
def server() -> Iterator[tuple[str, str]]:
    """`mani serve` from the full install on free ports, ready (model loaded); its HTTP URL and gRPC target."""
    port, grpc_port = free_port(), free_port()
    cmd = [sys.executable, "-m", "manifoundation.cli.main", "serve", "--port", str(port), "--grpc-port", str(grpc_port),
           "--workers", "1", "--log-level", "WARNING"]  # fmt: skip
    proc = subprocess.Popen(cmd, cwd=ROOT, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    url = f"http://127.0.0.1:{port}"
    try:
        deadline = time.monotonic() + 300
        while True:
            assert proc.poll() is None, f"mani serve exited with {proc.returncode}"
            assert time.monotonic() < deadline, "the server was not ready in 300 s"
            try:
                if httpx.get(f"{url}/readyz", timeout=2).status_code == 200:
                    break
            except httpx.HTTPError:
                pass
            time.sleep(0.5)
        yield url, f"127.0.0.1:{grpc_port}"
    finally:
        proc.terminate()
        try:
            proc.wait(timeout=30)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()


def _venv_megabytes(venv: Path) -> float:
    du = run(["du", "-sk", str(venv)], timeout=60).stdout.split()[0]
    return int(du) / 1024


def _record(wheel: Path) -> list[str]:
    """The files a wheel installs, from its RECORD (what `pip install` writes into site-packages)."""
    with zipfile.ZipFile(wheel) as archive:
        record = archive.read(next(n for n in archive.namelist() if n.endswith(".dist-info/RECORD"))).decode()
    return [line.split(",")[0] for line in record.splitlines() if line]


def test_each_wheel_adds_one_top_level_package_and_the_server_wheel_no_research(wheels: Path) -> None:
    (server,) = wheels.glob("manifoundation-*.whl")
    (client,) = wheels.glob("manifoundation_client-*.whl")
    assert len(list(wheels.glob("*.tar.gz"))) == 2
    for wheel in (server, client):
        tops = {name.split("/")[0] for name in _record(wheel) if ".dist-info/" not in name}
        assert tops == {"manifoundation"}, f"{wheel.name} installs {sorted(tops)}"
        assert "manifoundation/__init__.py" not in _record(wheel)  # a namespace shared by the two wheels
    server_files = _record(server)
    assert {n.split("/")[1] for n in server_files if n.startswith("manifoundation/")} == {"core", "server"}
    assert not [n for n in server_files if "research" in n.split("/")[:3] or "/bench" in n]
    assert "manifoundation/core/weights/cpu1k/model.safetensors" in server_files


def test_the_server_wheel_ships_no_client_code_and_requires_the_client_wheel(wheels: Path) -> None:
    (server,) = wheels.glob("manifoundation-*.whl")
    (client,) = wheels.glob("manifoundation_client-*.whl")
    with zipfile.ZipFile(server) as archive:
        names = archive.namelist()
        metadata = archive.read(next(n for n in names if n.endswith(".dist-info/METADATA"))).decode()
    assert not any(n.startswith(("manifoundation/contract/", "manifoundation/sdk/", "manifoundation/cli/"))
                   for n in names)  # fmt: skip
    assert any(n.startswith("manifoundation/server/api/") for n in names)
    version = client.name.split("-")[1]
    assert re.search(rf"^Requires-Dist: manifoundation-client\[[a-z,]+\]=={re.escape(version)}$", metadata, re.M)
    with zipfile.ZipFile(client) as archive:
        shipped = {n for n in archive.namelist() if n.startswith("manifoundation/")}
    client_dirs = ["manifoundation/contract", "manifoundation/sdk", "manifoundation/cli"]
    tracked = run(["git", "ls-files", *client_dirs], timeout=60, cwd=ROOT).stdout.split()
    assert shipped == {n for n in tracked if Path(n).suffix in {".py", ".pyi", ".proto", ".typed"}}


def test_the_client_wheel_alone_runs_the_quickstart(wheels: Path, server: tuple[str, str], tmp_path: Path) -> None:
    url, target = server
    (wheel,) = wheels.glob("manifoundation_client-*.whl")
    venv = tmp_path / "venv"
    clean = {k: v for k, v in os.environ.items() if not k.startswith(("PYTHON", "MANI_", "VIRTUAL_ENV"))}
    run([sys.executable, "-m", "venv", str(venv)], timeout=120, env=clean)
    python, mani = venv / "bin" / "python", venv / "bin" / "mani"
    started = time.monotonic()
    run([str(python), "-m", "pip", "install", "-q", str(wheel)], timeout=600, env=clean)
    install_s, megabytes = time.monotonic() - started, _venv_megabytes(venv)
    print(f"\nclient wheel alone: pip install {install_s:.1f} s, venv {megabytes:.0f} MB (du -sk)")

    work = tmp_path / "work"  # outside the repository: `clients` must come from the venv
    (work / "examples" / "data").mkdir(parents=True)
    shutil.copy(ROOT / "examples" / "data" / "box.npz", work / "examples" / "data" / "box.npz")
    (tmp_path / "probe").mkdir()
    (tmp_path / "probe" / "sitecustomize.py").write_text(PROBE)
    probe_out = tmp_path / "modules.jsonl"
    env = {**clean, "PYTHONPATH": str(tmp_path / "probe"), "MANI_URL": url, "MANI_PROBE_OUT": str(probe_out)}

    where = run([str(python), "-c", "import manifoundation.contract as c, importlib.util as u; print(c.__file__);"
                 "print(sorted(m for m in ('torch', 'manifoundation.server', 'manifoundation.core')"
                 " if u.find_spec(m)))"],
                timeout=60, cwd=work, env=env).stdout.split("\n")  # fmt: skip
    assert where[0].startswith(str(venv)) and where[1] == "[]", where

    quickstart = ["synthesize", "examples/data/box.npz", "--hand", "leap", "--task", "delta:0,0,0.05",
                  "--proposals", "4", "--out", "grasp.json"]  # fmt: skip
    refused = subprocess.run([str(mani), *quickstart, "--view", "grasp.html"], capture_output=True, text=True,
                             timeout=120, cwd=work, env=env)  # fmt: skip
    assert refused.returncode != 0 and "manifoundation-client[view]" in refused.stderr, refused.stderr
    assert not (work / "grasp.json").exists()  # refused before the job ran
    run([str(mani), *quickstart], timeout=300, cwd=work, env=env)
    result = SynthesisResult.model_validate_json((work / "grasp.json").read_bytes())
    assert result.hand.startswith("leap") and len(result.proposals) == 4

    run([str(python), "-m", "pip", "install", "-q", f"{wheel}[view,grpc]"], timeout=600, env=clean)
    print(f"with [view,grpc]: venv {_venv_megabytes(venv):.0f} MB")
    readme = (ROOT / "README.md").read_text()
    snippet = readme.split("The same from Python:\n\n```python\n", 1)[1].split("```", 1)[0]
    assert 'Client("http://127.0.0.1:8000")' in snippet
    run([str(python), "-c", snippet.replace("http://127.0.0.1:8000", url)], timeout=300, cwd=work, env=env)
    assert (work / "grasp.html").stat().st_size > 100_000  # plotly.js inlined: the view works offline
    grpc_call = ("from manifoundation.sdk.grpc_client import GrpcClient\n"
                 f"with GrpcClient({target!r}) as client:\n    print(len(client.robots()))")  # fmt: skip
    assert int(run([str(python), "-c", grpc_call], timeout=120, cwd=work, env=env).stdout) > 0

    processes = [json.loads(line) for line in probe_out.read_text().splitlines()]
    assert len(processes) >= 4
    for process in processes:
        assert not SERVER_PACKAGES & set(process["modules"]), process["argv"]
    assert install_s < MAX_INSTALL_S and megabytes < MAX_VENV_MB, (install_s, megabytes)
