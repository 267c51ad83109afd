"""`mani-lab bench network` registers as a plugin and runs (tiny settings)."""

from __future__ import annotations

import argparse

import pytest

from research.commands import bench_network


def test_register_and_run_tiny(capsys: pytest.CaptureFixture[str]) -> None:
    parser = argparse.ArgumentParser(prog="mani-lab bench")
    bench_network.register(parser.add_subparsers())
    args = parser.parse_args(
        ["network", "--configs", "cpu", "--batches", "1,2", "--iters", "2", "--warmup", "0", "--points", "300"]
    )
    assert args.func(args) == 0
    out = capsys.readouterr().out
    assert "p50 ms" in out and "samples/s" in out
    assert out.count("\ncpu ") == 2


def test_deformable_objects_run_the_deformable_head(capsys: pytest.CaptureFixture[str]) -> None:
    inputs = bench_network._inputs(300, 2, deformable=True)
    assert all("stretch" in i.properties for i in inputs)  # a deformable property opens the head
    parser = argparse.ArgumentParser(prog="mani-lab bench")
    bench_network.register(parser.add_subparsers())
    args = parser.parse_args(["network", "--configs", "cpu1k_deformable_gain", "--batches", "1", "--iters", "1",
                              "--warmup", "0", "--points", "300", "--deformable"])  # fmt: skip
    assert args.func(args) == 0
    out = capsys.readouterr().out
    assert "cloth objects" in out and out.count("\ncpu1k_deformable_gain ") == 1
