"""Worker processes, started, restarted and stopped the same way for both backends.

`mani serve`'s embedded queue keeps its `manifoundation.server.worker.child` processes on socketpairs; `mani worker`
keeps `manifoundation.server.worker.worker` processes on Redis. Both start a worker as ``python -m MODULE`` with the
queue settings as JSON in ``MANI_WORKER_SETTINGS``, slow down a worker that keeps dying before it is ready (`CrashLoop`;
a `mani worker` process says so on a pipe, `announce_ready`), and stop with SIGTERM (finish the current batch), then
SIGKILL after a grace period (`stop_all`).
"""

from __future__ import annotations

import contextlib
import os
import signal
import subprocess
import sys
import time
from collections.abc import Sequence

SETTINGS_ENV = "MANI_WORKER_SETTINGS"
READY_ENV = "MANI_READY_FD"
QUICK_DEATH_S = 5.0
"""A worker that dies within this many seconds of its start counts towards a crash loop (unless it said it was
ready: one killed while working is no crash loop)."""


def spawn(
    module: str, args: Sequence[str], settings_json: str, pass_fds: Sequence[int] = (),
    env: dict[str, str] | None = None,
) -> subprocess.Popen[bytes]:  # fmt: skip
    """Start ``python -m module *args`` with the settings (and ``env``) in its environment (stdin closed)."""
    process = subprocess.Popen(
        [sys.executable, "-m", module, *args],
        pass_fds=tuple(pass_fds),
        stdin=subprocess.DEVNULL,
        env=os.environ | {SETTINGS_ENV: settings_json} | (env or {}),
    )
    return process


class Child:
    """A worker process and the read end of the pipe on which it says it is ready (None: it never will)."""

    def __init__(self, process: subprocess.Popen[bytes], ready_fd: int | None = None) -> None:
        self.process = process
        self.born = time.monotonic()
        self._fd = ready_fd
        self._ready = False

    def ready(self) -> bool:
        """Whether the worker has said it is ready (reads the pipe without blocking)."""
        if self._fd is not None:
            try:
                said = os.read(self._fd, 1)
            except BlockingIOError:
                return False
            self._ready = said != b""  # b"": the worker exited without saying it
            os.close(self._fd)
            self._fd = None
        return self._ready


def spawn_ready(module: str, settings_json: str) -> Child:
    """`spawn` a worker that announces its readiness (`announce_ready`) on a pipe of its own."""
    read_fd, write_fd = os.pipe()
    os.set_blocking(read_fd, False)
    try:
        process = spawn(module, [], settings_json, pass_fds=(write_fd,), env={READY_ENV: str(write_fd)})
    finally:
        os.close(write_fd)
    return Child(process, read_fd)


def announce_ready() -> None:
    """In a worker started by `spawn_ready`: tell the supervisor that this worker is ready (once)."""
    fd = os.environ.pop(READY_ENV, None)
    if fd is not None:
        with contextlib.suppress(OSError):
            os.write(int(fd), b"1")
            os.close(int(fd))


class CrashLoop:
    """How long to wait before restarting a worker slot: nothing, unless it died quickly (and before it was
    ready) three times running."""

    def __init__(self) -> None:
        self._quick: dict[int, int] = {}

    def delay(self, slot: int, lived_s: float, ready: bool = False) -> float:
        """Seconds to wait before restarting ``slot``, whose worker lived ``lived_s`` seconds (``ready``: it had
        said it was ready)."""
        quick = self._quick.get(slot, 0) + 1 if lived_s < QUICK_DEATH_S and not ready else 0
        self._quick[slot] = quick
        return min(10.0, 0.5 * quick) if quick > 2 else 0.0


def stop_all(processes: Sequence[subprocess.Popen[bytes]], grace_s: float, *, signal_first: bool = True) -> None:
    """SIGTERM each live process (unless ``signal_first`` is False: they were told to stop another way), wait up
    to ``grace_s`` seconds for all of them together, then SIGKILL what is left."""
    if signal_first:
        for process in processes:
            if process.poll() is None:
                with contextlib.suppress(ProcessLookupError):
                    process.send_signal(signal.SIGTERM)
    end = time.monotonic() + grace_s
    for process in processes:
        try:
            process.wait(max(0.1, end - time.monotonic()))
        except subprocess.TimeoutExpired:
            with contextlib.suppress(ProcessLookupError):
                process.kill()
            process.wait()
