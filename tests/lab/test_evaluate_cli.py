"""`mani eval refine` runs end to end: a line per object in a log, the table, the ground-truth cache."""

from __future__ import annotations

import argparse
import pickle
from pathlib import Path

import pytest

from lab.evaluate import add_refine


def _parse(argv: list[str]) -> argparse.Namespace:
    p = argparse.ArgumentParser()
    add_refine(p.add_subparsers())
    return p.parse_args(argv)


def test_eval_refine_logs_progress_and_keeps_ground_truths(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    cache = tmp_path / "gt.pkl"
    argv = ["refine", "--hand", "panda_gripper", "--mode", "task", "--objects", "1", "--grasps", "1",
            "--ground-truth-cache", str(cache), "--json", str(tmp_path / "trials.json")]
    args = _parse(argv)
    assert args.func(args) == 0
    out = capsys.readouterr().out
    assert "panda_gripper task: 1/1 grasps" in out  # captured output is no terminal: plain progress lines
    assert "success %" in out
    store = pickle.load(cache.open("rb"))
    assert len(store) == 1
    candidates, rounds = next(iter(store.values()))
    assert rounds >= 1
    # a second run restores the grasps instead of sampling: the same trial outcome, the store unchanged
    args = _parse(argv)
    assert args.func(args) == 0
    again = pickle.load(cache.open("rb"))
    assert next(iter(again.values()))[1] == rounds
    assert len(next(iter(again.values()))[0]) == len(candidates)
