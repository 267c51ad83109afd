"""`mani-lab bench pipeline`: the worker times a real request's parts; the report's figures and identity test."""

from __future__ import annotations

import argparse

import numpy as np
import pytest

from research.commands.bench_pipeline import add_arguments, requests
from research.commands.bench_pipeline_report import identical, summary
from research.commands.bench_pipeline_worker import _Objects, _Timers, run_one

WEIGHTS = "manifoundation/core/weights/cpu1k"  # the shipped weights


def _record(wall: float, success: list[bool], answer: float = 0.0, audit: list[bool] | None = None) -> dict:
    parts = {"linearise": 0.02, "contacts": 0.01, "guards": 0.002, "solve": 0.01}
    calls = {f"{p}_calls": 2 for p in parts}
    return {"wall": wall, "stages": {"refinement": wall / 2}, **parts, **calls, "iterations": 2,
            "success": success, "answers": [[answer] * 10 for _ in success], "audit": audit}


def test_summary_figures() -> None:
    recs = [_record(0.1, [True], audit=[True]), _record(0.3, [False], audit=[False]),
            _record(0.2, [True], audit=[False])]
    s = summary(recs)
    assert s["p50"] == pytest.approx(0.2)
    assert s["verified_per_s"] == pytest.approx(2 / 0.6)
    assert s["best_success"] == pytest.approx(2 / 3)
    assert s["linearise_ms"] == pytest.approx(10.0)  # 0.06 s over 6 linearisations
    assert s["audit_best"] == pytest.approx(1 / 3)
    assert s["false_claims"] == 1  # the third: claimed, rejected


def test_identical_answers() -> None:
    assert identical(_record(0.1, [True]), _record(0.5, [True]))
    assert not identical(_record(0.1, [True]), _record(0.1, [False]))
    assert not identical(_record(0.1, [True]), _record(0.1, [True], answer=1e-6))


def test_requests_are_hand_major_and_audit_the_first() -> None:
    p = argparse.ArgumentParser()
    add_arguments(p)
    specs = requests(p.parse_args(["--hand", "leap,allegro", "--objects", "2", "--seeds", "2", "--audit", "3"]))
    assert [s["hand"] for s in specs] == ["leap"] * 4 + ["allegro"] * 4
    assert [s["audit"] for s in specs[:4]] == [True, True, True, False]


def test_object_order_asks_each_object_of_every_hand_in_a_row_with_the_same_requests() -> None:
    p = argparse.ArgumentParser()
    add_arguments(p)
    base = ["--hand", "leap,allegro", "--objects", "2", "--seeds", "2", "--audit", "3"]
    by_hand, by_object = requests(p.parse_args(base)), requests(p.parse_args([*base, "--order", "object"]))
    assert [(s["object"], s["seed"], s["hand"]) for s in by_object[:4]] == [
        (0, 0, "leap"), (0, 0, "allegro"), (0, 1, "leap"), (0, 1, "allegro")]  # fmt: skip
    key = lambda s: (s["hand"], s["object"], s["seed"])  # noqa: E731
    assert sorted(by_hand, key=key) == sorted(by_object, key=key)  # the same requests, audit marks included


def test_worker_times_a_real_request() -> None:
    import importlib

    refine_module = importlib.import_module("manifoundation.core.refine.refine")
    from manifoundation.core.robots import get_hand

    before = refine_module.linearise
    timers = _Timers()
    timers.install()
    spec = {"hand": "panda_gripper", "set": "box", "object": 0, "seed": 0, "task": "lift", "geometry": "mesh",
            "proposals": 1, "method": "random_contacts", "points": 1024, "audit": False,
            "box": "examples/data/box.npz"}
    try:
        rec = run_one(spec, _Objects(), timers)
    finally:
        timers.uninstall()
    assert refine_module.linearise is before
    assert rec["wall"] > 0 and len(rec["success"]) == 1 and rec["audit"] is None
    assert rec["linearise_calls"] >= 1 and rec["solve_calls"] >= 1
    assert 0 < rec["contacts"] <= rec["linearise"] < rec["wall"]
    assert np.isfinite(rec["answers"][0]).all() and len(rec["answers"][0]) == 7 + get_hand("panda_gripper").dof


def test_worker_runs_the_network_of_the_named_weights_and_says_where_contacts_came_from() -> None:
    spec = {"hand": "allegro", "set": "box", "object": 0, "seed": 0, "task": "lift", "geometry": "mesh",
            "proposals": 2, "method": "network", "weights": WEIGHTS, "points": 1024, "audit": False,
            "box": "examples/data/box.npz"}  # fmt: skip
    timers = _Timers()
    rec = run_one(spec, _Objects(), timers)
    assert rec["stages"]["network"] > 0
    assert len(rec["sources"]) == 2 and set(rec["sources"]) <= {"network", "random_fallback"}
    rec = run_one(dict(spec, method="random_contacts"), _Objects(), timers)
    assert rec["sources"] == ["random", "random"]


def test_summary_counts_flat_heatmaps() -> None:
    recs = [dict(_record(0.1, [True, True]), sources=["network", "random_fallback"]),
            dict(_record(0.1, [True]), sources=["random_fallback"])]  # fmt: skip
    assert summary(recs)["fallback"] == pytest.approx(2 / 3)


def test_largest_difference() -> None:
    from research.commands.bench_pipeline_report import largest_difference

    assert largest_difference(_record(0.1, [True]), _record(0.2, [True], answer=3e-7)) == pytest.approx(3e-7)
    assert largest_difference(_record(0.1, [True]), _record(0.2, [True, False])) == float("inf")


def test_third_party_specs_name_their_files() -> None:
    """Each third-party spec names its object's file: a reference checkout with fewer candidates loads the same."""
    p = argparse.ArgumentParser()
    add_arguments(p)
    specs = requests(p.parse_args(["--hand", "allegro", "--objects", "2", "--seeds", "1"]))
    assert [s["name"] for s in specs] == ["kettle_handle", "micro_handle"]
    assert all(s["path"].endswith(".stl") for s in specs)
