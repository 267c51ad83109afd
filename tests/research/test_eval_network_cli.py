"""`mani-lab eval network` end to end on a tiny generated data set: a success row and a property row per weights,
and ``DIR@S`` evaluating the same weights at another prior scale."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from tests.research.tiny_data import cli, tiny_test_set

SHIPPED = "manifoundation/core/weights/cpu1k"  # the shipped weights


@pytest.mark.slow
def test_eval_network_prints_a_row_per_weights_and_scale(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    p = cli()
    out = tiny_test_set(tmp_path / "tiny")
    run = p.parse_args(["eval", "network", "--data", str(out), "--cases", "3", "--budgets", "2", "--no-audit",
                        "--no-random", "--samples", "4", "--proposals", "2", "--no-progress",
                        "--weights", f"{SHIPPED},{SHIPPED}@0"])  # fmt: skip
    assert run.func(run) == 0
    text = capsys.readouterr().out
    rows = {
        line.split("|")[1].strip(): line
        for line in text.splitlines()
        if line.startswith("| manifoundation/core/weights")
    }
    assert set(rows) == {"manifoundation/core/weights/cpu1k", "manifoundation/core/weights/cpu1k@0"}
    distinct = {name: float(line.strip("|").split("|")[3]) for name, line in rows.items()}
    assert distinct["manifoundation/core/weights/cpu1k@0"] <= 1.0  # z = 0 for every sample: one contact set at most
    assert sum("| network (manifoundation/core/weights/cpu1k" in line for line in text.splitlines()) == 2


@pytest.mark.slow
def test_resampled_regions_only_raise_the_top_point_figure(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """The union of the data's region and re-sampled ones contains the data's: the top point hits it at least as
    often, and a random point too."""
    p = cli()
    out = tiny_test_set(tmp_path / "tiny")
    run = p.parse_args(["eval", "network", "--data", str(out), "--cases", "4", "--budgets", "1", "--no-audit",
                        "--no-random", "--samples", "4", "--proposals", "1", "--no-progress", "--resamples", "2",
                        "--workers", "1"])  # fmt: skip
    assert run.func(run) == 0
    text = capsys.readouterr().out
    assert "top point in the union of 3 valid regions (a lower bound)" in text
    row = next(line for line in text.splitlines() if line.startswith("| manifoundation/core/weights/cpu1k |"))
    cells = [c.strip() for c in row.strip("|").split("|")]
    data_hit, data_share = re.findall(r"(\d+)%", cells[2])
    union_hit, union_share = re.findall(r"(\d+)%", cells[3])
    assert int(union_hit) >= int(data_hit) and int(union_share) >= int(data_share)
    assert len(cells) == 7


@pytest.mark.slow
def test_eval_network_adds_the_deformable_goals_beside_their_random_baselines(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``--deformables N``: one command prints the rigid table and, for every material, the network against the
    paper's random baseline and random points with the target's motion, with the goal judged against each."""
    import json

    p = cli()
    out = tiny_test_set(tmp_path / "tiny")
    report = tmp_path / "figures.json"
    run = p.parse_args(["eval", "network", "--data", str(out), "--cases", "2", "--budgets", "1", "--no-audit",
                        "--no-random", "--samples", "2", "--proposals", "1", "--no-progress", "--deformables", "1",
                        "--json", str(report)])  # fmt: skip
    assert run.func(run) == 0
    text = capsys.readouterr().out
    for material in ("cloth", "rope", "plasticine"):
        assert re.search(rf"{material}: network [\d.]+ % on unseen objects against the paper's baseline", text)
        assert re.search(rf"{material}: network [\d.]+ % on unseen objects against random points with the target", text)
    rows = json.loads(report.read_text())["deformables"]["table"]
    assert {(r["material"], r["method"]) for r in rows} == {
        (m, k) for m in ("cloth", "rope", "plasticine") for k in ("random_motion", "random_target_motion", "network")
    }
    assert all(r["cases"] == 1 and r["split"] == "test_uo" for r in rows)
