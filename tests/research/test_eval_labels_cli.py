"""`mani-lab eval labels` end to end on a tiny generated data set: the table with the data's and a re-sampled row, a
column per weights."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.research.tiny_data import cli, tiny_test_set


@pytest.mark.slow
def test_eval_labels_prints_each_label_source(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    p = cli()
    out = tiny_test_set(tmp_path / "tiny")
    shipped = "manifoundation/core/weights/cpu1k"
    weights = f"{shipped},{shipped}"  # the same twice: two columns, equal figures
    run = p.parse_args(["eval", "labels", "--data", str(out), "--resamples", "1", "--workers", "1", "--samples", "2",
                        "--weights", weights])  # fmt: skip
    assert run.func(run) == 0
    text = capsys.readouterr().out
    assert "| the data's (its own sampling run) |" in text and "| re-sampling 1 |" in text
    union = next(line for line in text.splitlines() if line.startswith("| union of the 2 |"))
    cells = [c.strip() for c in union.strip("|").split("|")]
    assert len(cells) == 4 and cells[2] == cells[3]
