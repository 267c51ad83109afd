"""Worker processes' readiness pipe and the crash-loop back-off built on it."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import pytest

from manifoundation.server.worker.supervisor import Child, CrashLoop, spawn_ready


def _wait_exit(child: Child) -> None:
    child.process.wait(timeout=30)


@pytest.mark.parametrize(("announces", "expected"), [(True, True), (False, False)])
def test_the_ready_pipe_tells_a_worker_that_said_so_from_one_that_died_first(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path, announces: bool, expected: bool
) -> None:
    # a stand-in module for the worker: `python -m` runs it with the pipe's write end in MANI_READY_FD
    script = (
        "from manifoundation.server.worker.supervisor import announce_ready; announce_ready()"
        if announces
        else "import sys"
    )
    monkeypatch.setattr("manifoundation.server.worker.supervisor.sys.executable", _python_running(script, tmp_path))
    child = spawn_ready("unused", json.dumps({}))
    _wait_exit(child)
    assert child.ready() is expected
    assert child.ready() is expected  # read once, remembered


def test_a_worker_that_was_ready_never_counts_towards_a_crash_loop() -> None:
    loop = CrashLoop()
    assert [loop.delay(0, 0.5) for _ in range(4)] == [0.0, 0.0, 1.5, 2.0]  # died before ready, four times
    assert loop.delay(0, 0.5, ready=True) == 0.0  # killed while working: restarted at once, the count reset
    assert loop.delay(0, 0.5) == 0.0


def _python_running(code: str, directory: Path) -> str:
    """A path to an executable that ignores ``-m MODULE`` and runs ``code`` in this interpreter."""
    wrapper = directory / "python"
    wrapper.write_text(f"#!/bin/sh\nexec {sys.executable} -c '{code}'\n")
    wrapper.chmod(0o755)
    return str(wrapper)
