"""`mani-lab eval refine` runs end to end: a line per object in a log, the table, the ground-truth cache."""

from __future__ import annotations

import argparse
import pickle
from pathlib import Path

import pytest

from research.commands.evaluate import add_refine

SHIPPED = "manifoundation/core/weights/cpu1k"  # the shipped weights


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


# 20 s: a whole `mani-lab eval deformable` run beside its random baseline: `make test-slow`
@pytest.mark.slow
def test_eval_deformable_judges_the_goal_only_beside_a_random_baseline(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from research.commands.eval_deformable import add_deformable

    p = argparse.ArgumentParser()
    add_deformable(p.add_subparsers())
    common = ["deformable", "--materials", "rope", "--splits", "test_uo", "--cases", "1", "--weights",
              SHIPPED, "--sensitivity", "1", "--json", str(tmp_path / "f.json")]  # fmt: skip
    args = p.parse_args([*common, "--methods", "network"])
    assert args.func(args) == 0
    out = capsys.readouterr().out
    assert "no random baseline in this run" in out and "not met" not in out
    args = p.parse_args([*common, "--methods", "random_target_motion,network"])
    assert args.func(args) == 0
    out = capsys.readouterr().out
    assert "against random points with the target's motion" in out and "no random baseline" not in out
    assert "paper's baseline" not in out
    import json

    [pair] = json.loads((tmp_path / "f.json").read_text())["sensitivity"]
    assert pair["pair"] == "rope/stick" and len(pair["matched_error"]) == 1 and len(pair["swapped_error"][0]) == 2
    args = p.parse_args([*common, "--methods", "random_motion,network", "--sensitivity", "0"])
    assert args.func(args) == 0
    out = capsys.readouterr().out
    assert "against the paper's baseline" in out and "with the target's motion" not in out
    # the service asked for K answers: the rollout-checked network against random contacts at the same budget
    args = p.parse_args([*common, "--methods", "network_samples,network_checked,random_checked", "--proposals", "2",
                         "--sensitivity", "0"])
    assert args.func(args) == 0
    out = capsys.readouterr().out
    assert "network_checked" in out and "network_samples" in out
    assert "network_checked" in out.split("checked by the same rollouts")[0].splitlines()[-1]
    assert "network_samples" not in "".join(line for line in out.splitlines() if "checked by the same" in line)


def test_eval_deformable_prints_the_property_figure_for_each_member(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    import json

    from research.commands.eval_deformable import add_deformable

    p = argparse.ArgumentParser()
    add_deformable(p.add_subparsers())
    args = p.parse_args(["deformable", "--materials", "rope", "--splits", "test_uo", "--cases", "1", "--methods",
                         "random_motion", "--figure", "1", "--json", str(tmp_path / "f.json")])  # fmt: skip
    assert args.func(args) == 0  # no network method asked for: the figure loads the weights itself
    out = capsys.readouterr().out
    assert "property figure" in out and "stick" in out
    rows = json.loads((tmp_path / "f.json").read_text())["figure"]
    assert [r[0]["name"] for r in rows] == ["rope", "stick"]
    assert set(rows[1][0]["candidates"]) == {"front_pair", "front_one", "centre", "rear_one", "rear_pair", "far_pair"}


def test_eval_deformable_counts_the_figure_per_latent_sample_and_refuses_samples_without_shapes(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    import json

    from research.commands.eval_deformable import add_deformable

    p = argparse.ArgumentParser()
    add_deformable(p.add_subparsers())
    base = ["deformable", "--materials", "rope", "--splits", "test_uo", "--cases", "1", "--methods", "random_motion"]
    args = p.parse_args([*base, "--figure-samples", "2"])
    assert args.func(args) == 2
    assert "--figure-samples" in capsys.readouterr().out
    args = p.parse_args([*base, "--figure", "1", "--figure-samples", "2", "--json", str(tmp_path / "f.json")])
    assert args.func(args) == 0
    assert "per latent sample" in capsys.readouterr().out
    rows = json.loads((tmp_path / "f.json").read_text())["figure_samples"]
    assert [(r["name"], r["answers"]) for r in rows] == [("rope", 2), ("stick", 2)]
    for r in rows:
        assert r["ahead"] + r["behind"] == 2 and r["reaches"] == r["ahead_reaching"] + r["behind_reaching"]


def test_the_figure_counts_own_answers_ahead_of_and_behind_the_centre_with_their_successes() -> None:
    from research.commands.eval_deformable import _ahead_behind
    from research.evaluation.property_pairs import FigureMember

    def member(along: float, reaches: bool, source: str = "network") -> FigureMember:
        return FigureMember("handkerchief", reaches, True, along, source, {})

    members = [member(0.4, True), member(0.0, False), member(-0.3, False), member(-0.5, True),
               member(-0.2, True, "motion_fallback")]  # fmt: skip
    assert _ahead_behind(members) == "2 (1) / 2 (1)"  # the fallback's answer is not the network's own
