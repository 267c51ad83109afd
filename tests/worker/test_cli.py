"""`mani worker`'s supervisor: a crash-looping slot waits its back-off without holding up the other slots."""

from __future__ import annotations

import itertools
import json
import signal
import subprocess
import sys
import textwrap
import time

# Slot 0's process exits at once, every time, never ready (a crash loop: its back-off grows to seconds); slot 1's
# is ready (its pipe says so), lives 2.5 s, exits, and must be started again at once although slot 0 is waiting.
SCRIPT = textwrap.dedent(
    """
    import json, os, subprocess, sys, time
    from manifoundation.server.worker.cli import keep_alive
    from manifoundation.server.worker.supervisor import Child

    def start(slot):
        print(json.dumps({"slot": slot, "t": time.monotonic()}), flush=True)
        lives = 0.0 if slot == 0 else 2.5
        process = subprocess.Popen([sys.executable, "-c", f"import time; time.sleep({lives})"])
        if slot == 0:
            return Child(process)
        read_fd, write_fd = os.pipe()
        os.write(write_fd, b"1")
        os.close(write_fd)
        return Child(process, read_fd)

    sys.exit(keep_alive(start, 2))
    """
)


def test_a_crash_looping_slot_does_not_delay_the_restart_of_another() -> None:
    proc = subprocess.Popen([sys.executable, "-c", SCRIPT], stdout=subprocess.PIPE, text=True)
    try:
        time.sleep(4.5)
    finally:
        proc.send_signal(signal.SIGTERM)
        out, _ = proc.communicate(timeout=30)
    starts = [json.loads(line) for line in out.splitlines() if line.startswith("{")]
    slot0 = [s["t"] for s in starts if s["slot"] == 0]
    slot1 = [s["t"] for s in starts if s["slot"] == 1]
    assert len(slot1) >= 2, starts
    gaps0 = [b - a for a, b in itertools.pairwise(slot0)]
    assert max(gaps0) > 1.0, f"slot 0 should be in a crash-loop back-off: {gaps0}"
    # slot 1's worker lived 2.5 s (plus its interpreter's start-up); it is back within a poll or two of its exit
    assert slot1[1] - slot1[0] < 2.5 + 0.8, f"slot 1 restarted {slot1[1] - slot1[0]:.2f} s after its start"
