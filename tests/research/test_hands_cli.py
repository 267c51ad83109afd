"""`mani hands` and `mani-lab bench hands` run end to end (offline HTML: plotly inlined, no CDN)."""

from __future__ import annotations

import argparse
from pathlib import Path

import pytest

from manifoundation.server.commands import hands
from research.commands import bench_hands


def _parse(register, argv: list[str]) -> argparse.Namespace:  # type: ignore[no-untyped-def]
    p = argparse.ArgumentParser()
    register(p.add_subparsers())
    return p.parse_args(argv)


def test_list(capsys: pytest.CaptureFixture[str]) -> None:
    args = _parse(hands.register, ["hands"])
    assert args.func(args) == 0
    out = capsys.readouterr().out
    for name in ("allegro", "leap", "shadow", "panda_gripper", "barrett", "kinova3f"):
        assert name in out


def test_show_writes_offline_html(tmp_path: Path) -> None:
    out = tmp_path / "panda.html"
    args = _parse(hands.register, ["hands", "show", "panda_gripper", "--html", str(out)])
    assert args.func(args) == 0
    html = out.read_text()
    assert '<script src="http' not in html  # nothing fetched: plotly.js is inlined
    assert len(html) > 1_000_000 and "Plotly.newPlot" in html


def test_show_unknown_hand(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    args = _parse(hands.register, ["hands", "show", "nope", "--html", str(tmp_path / "x.html")])
    assert args.func(args) == 2
    assert "allegro" in capsys.readouterr().out


def test_bench_runs(capsys: pytest.CaptureFixture[str]) -> None:
    args = _parse(
        bench_hands.register,
        ["hands", "--hands", "panda_gripper", "--batches", "1", "--iters", "2", "--sdf-points", "512"],
    )
    assert args.func(args) == 0
    out = capsys.readouterr().out
    assert "panda_gripper" in out and "KD-tree" in out
