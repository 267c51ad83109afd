"""`mani eval network` end to end on a tiny generated data set: a success row and a property row per weights,
and ``DIR@S`` evaluating the same weights at another prior scale."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.lab.tiny_data import cli, tiny_test_set


@pytest.mark.slow
def test_eval_network_prints_a_row_per_weights_and_scale(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    p = cli()
    out = tiny_test_set(tmp_path / "tiny")
    run = p.parse_args(["eval", "network", "--data", str(out), "--cases", "3", "--budgets", "2", "--no-audit",
                        "--no-random", "--samples", "4", "--proposals", "2", "--no-progress",
                        "--weights", "models/weights/cpu1k,models/weights/cpu1k@0"])  # fmt: skip
    assert run.func(run) == 0
    text = capsys.readouterr().out
    rows = {line.split("|")[1].strip(): line for line in text.splitlines() if line.startswith("| models/weights")}
    assert set(rows) == {"models/weights/cpu1k", "models/weights/cpu1k@0"}
    distinct = {name: float(line.strip("|").split("|")[3]) for name, line in rows.items()}
    assert distinct["models/weights/cpu1k@0"] <= 1.0  # z = 0 for every sample: one contact set at most
    assert sum("| network (models/weights/cpu1k" in line for line in text.splitlines()) == 2
