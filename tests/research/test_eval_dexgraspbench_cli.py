"""`mani-lab eval dexgraspbench`: refuses clearly without DGB's one-time setup; with it (slow), runs a few answers
through both tests.

The slow test needs DexGraspBench's work tree and venv (research/benchmarks/dexgraspbench/README.md) named by
``$DGB_SRC`` and ``$DGB_PYTHON``; without them it is skipped, saying so.
"""

from __future__ import annotations

import argparse
import json
import os
from pathlib import Path

import pytest

from research.commands.eval_dexgraspbench import add_dexgraspbench_parser, armatures, setup_problem
from research.commands.eval_physics import add_physics_parser


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser()
    sub = p.add_subparsers()
    add_dexgraspbench_parser(sub)
    add_physics_parser(sub)
    return p


def test_without_the_setup_it_says_how_and_exits_2(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    args = _parser().parse_args(["dexgraspbench", "--dgb-dir", str(tmp_path), "--dgb-python", str(tmp_path / "py")])
    assert args.func(args) == 2
    out = capsys.readouterr().out
    assert "not set up" in out and "research/benchmarks/dexgraspbench/README.md" in out
    assert setup_problem(None, None) is not None


def test_armature_variants() -> None:
    from manifoundation.core.physics import Protocol

    assert armatures("fetched,ours,0.005") == [None, Protocol().armature_revolute, 0.005]
    with pytest.raises(ValueError):
        armatures("heavy")


DGB_SRC, DGB_PYTHON = os.environ.get("DGB_SRC"), os.environ.get("DGB_PYTHON")
SKIP = setup_problem(DGB_SRC, DGB_PYTHON)


@pytest.mark.slow
@pytest.mark.skipif(SKIP is not None, reason=f"DexGraspBench copy/venv absent ({SKIP}); one-time setup: "
                    "research/benchmarks/dexgraspbench/README.md, then set $DGB_SRC and $DGB_PYTHON")  # fmt: skip
def test_answers_go_through_both_tests(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    physics = tmp_path / "physics.json"
    p = _parser()
    args = p.parse_args(["physics", "--hand", "leap_hand,allegro", "--objects", "1", "--json", str(physics)])
    args.func(args)
    out = tmp_path / "dgb.json"
    args = p.parse_args(["dexgraspbench", "--json-in", str(physics), "--armature", "fetched,ours", "--workdir",
                         str(tmp_path / "work"), "--json", str(out)])  # fmt: skip
    assert args.func(args) == 0
    verdicts = json.loads(out.read_text())
    assert len(verdicts) == 2 * 2  # two answers, two armature variants
    for v in verdicts:
        assert isinstance(v["held"], bool) and v["resets"] >= 0 and v["delta_pos"] >= 0
        assert v["held"] == (v["succ_flag"] and v["resets"] == 0)
        assert v["fk_mm"] < 1e-3  # LEAP Hand and Allegro: the same kinematics as DGB's
    assert "DGB − ours" in capsys.readouterr().out
