"""`mani-lab data generate` names a hand it does not know instead of writing a data set without examples."""

from __future__ import annotations

import argparse
from pathlib import Path

import pytest

from research.commands import data
from research.data.generate import available_hands


def _parse(argv: list[str]) -> argparse.Namespace:
    p = argparse.ArgumentParser()
    data.register(p.add_subparsers())
    return p.parse_args(argv)


def test_an_unknown_hand_is_refused_by_name(tmp_path: Path) -> None:
    args = _parse(["data", "generate", "--out", str(tmp_path / "d"), "--objects", "1", "--hands", "allegro,nohand",
                   "--held-out-hands", "", "--no-progress"])  # fmt: skip
    with pytest.raises(SystemExit, match="unknown nohand"):
        args.func(args)
    assert not (tmp_path / "d").exists()


def test_an_old_hand_name_is_a_hand_the_generator_labels() -> None:
    # `leap` is the old name of leap_kaizen: it was skipped, and its data set came out empty
    assert available_hands(("leap", "leap_kaizen", "nohand")) == ["leap", "leap_kaizen"]
