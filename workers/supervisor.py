"""Worker processes, started, restarted and stopped the same way for both backends.

`mani serve`'s embedded queue keeps its `workers.child` processes on socketpairs; `mani worker` keeps
`workers.worker` processes on Redis. Both start a worker as ``python -m MODULE`` with the queue settings as JSON
in ``MANI_WORKER_SETTINGS``, slow down a worker that keeps dying right after its start (`CrashLoop`), and stop
with SIGTERM (finish the current batch), then SIGKILL after a grace period (`stop_all`).
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
QUICK_DEATH_S = 5.0
"""A worker that dies within this many seconds of its start counts towards a crash loop."""


def spawn(
    module: str, args: Sequence[str], settings_json: str, pass_fds: Sequence[int] = ()
) -> subprocess.Popen[bytes]:
    """Start ``python -m module *args`` with the settings in its environment (stdin closed)."""
    process = subprocess.Popen(
        [sys.executable, "-m", module, *args],
        pass_fds=tuple(pass_fds),
        stdin=subprocess.DEVNULL,
        env=os.environ | {SETTINGS_ENV: settings_json},
    )
    return process


class CrashLoop:
    """How long to wait before restarting a worker slot: nothing, unless it died quickly three times running."""

    def __init__(self) -> None:
        self._quick: dict[int, int] = {}

    def delay(self, slot: int, lived_s: float) -> float:
        """Seconds to wait before restarting ``slot``, whose worker lived ``lived_s`` seconds."""
        quick = self._quick.get(slot, 0) + 1 if lived_s < QUICK_DEATH_S else 0
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
