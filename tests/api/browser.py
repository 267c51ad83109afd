"""Headless Chromium for the page tests: dump the DOM after the scripts ran, and take a screenshot."""

from __future__ import annotations

import shutil
import subprocess
import tempfile
from pathlib import Path

import pytest

FLAGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--no-first-run",
    "--hide-scrollbars",
    "--enable-unsafe-swiftshader",
]
ARTIFACTS = Path(__file__).resolve().parents[2] / "artifacts" / "service"


def chromium() -> str:
    """Path of the Chromium binary, or skip the test with the reason."""
    for name in ("chromium", "chromium-browser", "google-chrome"):
        path = shutil.which(name)
        if path:
            return path
    pytest.skip("chromium is not installed (apt-get install chromium; .ci/run installs it)")


def _run(url: str, extra: list[str], budget_ms: int, timeout: float) -> subprocess.CompletedProcess[str]:
    # Chromium's helper processes may still write to the profile as it exits: a failed clean-up is not a failure
    with tempfile.TemporaryDirectory(prefix="mani-chromium-", ignore_cleanup_errors=True) as profile:
        cmd = [chromium(), *FLAGS, f"--user-data-dir={profile}", f"--virtual-time-budget={budget_ms}", *extra, url]
        return subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, check=False)


def dump_dom(url: str, budget_ms: int = 6000, timeout: float = 150) -> str:
    """The page's DOM after its scripts ran for ``budget_ms`` of virtual time."""
    done = _run(url, ["--dump-dom"], budget_ms, timeout)
    assert done.returncode == 0, done.stderr[-2000:]
    return done.stdout


def screenshot(url: str, name: str, budget_ms: int = 6000, timeout: float = 150) -> Path:
    """A PNG of the page under ``artifacts/service/`` (git-ignored), returned."""
    ARTIFACTS.mkdir(parents=True, exist_ok=True)
    path = ARTIFACTS / name
    path.unlink(missing_ok=True)
    done = _run(url, [f"--screenshot={path}", "--window-size=1400,1000"], budget_ms, timeout)
    assert done.returncode == 0 and path.is_file(), done.stderr[-2000:]
    return path
