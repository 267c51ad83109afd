"""`stopped_at`: work still running at its deadline is answered and its process ends, whether the work runs Python
(the watchdog thread answers and exits) or holds the interpreter in native code (the timer signal ends it); work
done in time leaves the process as it was."""

from __future__ import annotations

import signal
import subprocess
import sys
import time

import pytest

from manifoundation.server.worker.overrun import EXIT_OVERRUN, HARD_STOP_S

BODIES = {
    "python": "while True:\n        sum(range(1000))",
    "native": 're.match(r"(a+)+$", "a" * 40 + "b")',  # the regex engine holds the GIL throughout
    "quick": "time.sleep(0.1)",
}
SCRIPT = """
import re, time
from manifoundation.server.worker.overrun import stopped_at
with stopped_at(time.time() + {deadline}, lambda: print("answered", flush=True)):
    {body}
print("finished", flush=True)
"""


@pytest.mark.parametrize(
    ("body", "code", "out", "after"),
    [
        ("python", EXIT_OVERRUN, "answered", 0.0),
        ("native", -signal.SIGALRM, "", HARD_STOP_S),
        ("quick", 0, "finished", 0.0),
    ],
)
def test_work_outliving_its_deadline_ends_its_process(body: str, code: int, out: str, after: float) -> None:
    deadline = 1.0
    t0 = time.monotonic()
    script = SCRIPT.format(deadline=deadline, body=BODIES[body])
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=30)
    elapsed = time.monotonic() - t0
    assert (done.returncode, done.stdout.split()) == (code, [out] if out else [])
    if body != "quick":  # ended at the deadline (the watchdog) or a hard stop later (the timer), not after the work
        assert deadline + after - 0.05 < elapsed < deadline + after + 1.5, elapsed


def test_a_deadline_already_past_runs_nothing() -> None:
    from manifoundation.server.worker.overrun import DeadlinePassed, stopped_at

    ran = []
    with pytest.raises(DeadlinePassed), stopped_at(time.time() - 1, lambda: None):
        ran.append(1)
    assert not ran
