"""The payload spool's directories: one a killed process left behind is removed by the next spool made; one a
live process holds is not, whatever its age."""

from __future__ import annotations

import os
import subprocess
import sys
import time

from manifoundation.server.spool import new_spool, remove_spool, stale_spools

MAKE = "from manifoundation.server.spool import new_spool; import os, sys, time; print(new_spool(), flush=True); "


def _spool_of(code: str) -> tuple[subprocess.Popen[str], str]:
    proc = subprocess.Popen([sys.executable, "-c", MAKE + code], stdout=subprocess.PIPE, text=True)
    assert proc.stdout is not None
    return proc, proc.stdout.readline().strip()


def test_a_killed_processs_spool_goes_and_a_live_ones_stays() -> None:
    live, held = _spool_of("time.sleep(60)")
    dead, left = _spool_of("os._exit(0)")  # ends without removing its spool, as a killed process would
    dead.wait(30)
    try:
        an_hour_ago = time.time() - 3600
        for path in (held, left):
            os.utime(path, (an_hour_ago, an_hour_ago))
        stale = stale_spools(os.path.dirname(left))
        assert left in stale and held not in stale
        recent = stale_spools(os.path.dirname(left), min_age_s=7200)
        assert left not in recent  # too recent to judge
        mine = new_spool()  # removes the stale ones first
        assert not os.path.exists(left) and os.path.exists(held) and mine not in stale_spools(min_age_s=0)
        remove_spool(mine)
        assert not os.path.exists(mine)
    finally:
        live.kill()
        live.wait(30)
        remove_spool(held)
