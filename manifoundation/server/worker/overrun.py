"""Work that a deadline really stops: at the deadline the worker process running it answers for it, then ends
itself, and its supervisor replaces it (the embedded pump on its pipe's EOF, `mani worker`'s `keep_alive`), as it
replaces any worker that dies. Waiting less is not enough: a worker still loading a hostile robot description after
its caller gave up is a worker no job can use.

Two clocks, so that no loader can outlive its deadline by more than `HARD_STOP_S`:

- a watchdog thread wakes at the deadline, calls the shell's ``answer`` (the caller is told why, at once) and ends the
  process (``os._exit(EXIT_OVERRUN)``); it runs whenever the loader lets the interpreter switch threads (Python code
  does every few milliseconds);
- a timer signal (``SIGALRM``, left to its default action: the kernel ends the process) fires `HARD_STOP_S` after
  the deadline, for a loader stuck in native code that never lets the watchdog run. Its caller is then told by the
  service side (`manifoundation.server.queue.records.overrun_error`).

The work runs in the worker's main thread (the timer signal is armed only there).
"""

from __future__ import annotations

import contextlib
import logging
import os
import signal
import threading
import time
from collections.abc import Callable, Iterator

log = logging.getLogger("manifoundation.server.worker.overrun")

EXIT_OVERRUN = 75
"""The exit code of a worker that ended itself at a deadline (what its supervisor logs)."""
HARD_STOP_S = 1.0
"""Seconds after the deadline at which the timer signal ends a worker whose watchdog could not run."""


class DeadlinePassed(Exception):
    """The work's deadline had passed before it started (it was not run)."""


@contextlib.contextmanager
def stopped_at(deadline: float | None, answer: Callable[[], None]) -> Iterator[None]:
    """Run the ``with`` body in this process until ``deadline`` (epoch seconds; None: no deadline). If it is still
    running then, ``answer()`` is called from the watchdog thread and the process ends (see module doc).

    Raises:
        DeadlinePassed: ``deadline`` is already past (nothing runs).
    """
    if deadline is None:
        yield
        return
    left = deadline - time.time()
    if left <= 0:
        raise DeadlinePassed(f"its deadline passed {-left:.1f} s before it started")
    claim = threading.Lock()  # held by whichever side ends the work: the body finishing, or the watchdog
    finished = threading.Event()

    def watch() -> None:
        if finished.wait(left) or not claim.acquire(blocking=False):
            return
        try:
            log.warning("deadline passed while running: answering, then ending this worker (it is replaced)")
            answer()
        except Exception:
            log.exception("could not answer for the work stopped at its deadline")
        finally:
            os._exit(EXIT_OVERRUN)

    armed = _arm(left + HARD_STOP_S)
    threading.Thread(target=watch, name="mani-deadline", daemon=True).start()
    try:
        yield
    finally:
        if armed:
            signal.setitimer(signal.ITIMER_REAL, 0)
        finished.set()
        if not claim.acquire(blocking=False):  # the watchdog is answering: this process ends in a moment
            threading.Event().wait()


def _arm(seconds: float) -> bool:
    """Arm the hard stop (main thread only, and only where SIGALRM still has its default action)."""
    if threading.current_thread() is not threading.main_thread():
        return False
    if signal.getsignal(signal.SIGALRM) not in (signal.SIG_DFL, None):
        return False
    signal.setitimer(signal.ITIMER_REAL, seconds)
    return True
