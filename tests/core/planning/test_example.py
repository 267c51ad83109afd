"""`examples/planner_waypoints.py` end to end (the cup into the box; ≈ 20 s, so slow)."""

import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[3]


@pytest.mark.slow
def test_cup_in_the_box_example_runs_and_every_step_is_verified(tmp_path):
    env = {**os.environ, "PYTHONPATH": str(ROOT), "OMP_NUM_THREADS": "1"}
    run = subprocess.run([sys.executable, str(ROOT / "examples" / "planner_waypoints.py"), "--write-plan",
                          str(tmp_path)], cwd=ROOT, env=env, capture_output=True, text=True, timeout=600)  # fmt: skip
    assert run.returncode == 0, run.stdout + run.stderr
    assert "waypoints[1] repaired" in run.stdout and "kettle" in run.stdout
    assert "plan succeeded" in run.stdout
    assert (tmp_path / "plan.yaml").is_file() and (tmp_path / "cup.npz").is_file()
