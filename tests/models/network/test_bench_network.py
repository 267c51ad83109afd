"""`mani bench network` registers as a plugin and runs (tiny settings)."""

from __future__ import annotations

import argparse

import pytest

from lab import bench_network


def test_register_and_run_tiny(capsys: pytest.CaptureFixture[str]) -> None:
    parser = argparse.ArgumentParser(prog="mani bench")
    bench_network.register(parser.add_subparsers())
    args = parser.parse_args(
        ["network", "--configs", "cpu", "--batches", "1,2", "--iters", "2", "--warmup", "0", "--points", "300"]
    )
    assert args.func(args) == 0
    out = capsys.readouterr().out
    assert "p50 ms" in out and "samples/s" in out
    assert out.count("\ncpu ") == 2
