"""`mani plan` and `mani-lab bench plan` (manifoundation/server/commands/plan.py, research/commands/bench_plan.py) on
small real problems."""

import argparse
import json

import numpy as np
import yaml

from manifoundation.server.commands import plan
from research.commands import bench_plan


def _parser():
    parser = argparse.ArgumentParser()
    sub = parser.add_subparsers()
    plan.register(sub)
    bench = sub.add_parser("bench").add_subparsers()
    bench_plan.register(bench)
    return parser


def test_mani_plan_prints_the_summary_and_writes_json_and_html(block, tmp_path, capsys):
    mesh, pts, nrm = block
    np.savez(tmp_path / "block.npz", points=pts, normals=nrm, vertices=mesh.vertices, faces=mesh.faces)
    wall = {"kind": "box", "name": "wall", "size": [0.02, 0.4, 0.3], "pose": {"position": [0, 0, 0.15]}}
    spec = {"object": {"file": "block.npz"}, "robot": {"name": "allegro"}, "start": {"position": [-0.15, 0, 0.1]},
            "waypoints": [{"position": [0.0, 0, 0.1]}, {"position": [0.15, 0, 0.1]}],
            "scene": {"support_plane": {"height": 0}, "obstacles": [wall]}}  # fmt: skip
    (tmp_path / "plan.yaml").write_text(yaml.safe_dump(spec))
    args = _parser().parse_args([
        "plan", str(tmp_path / "plan.yaml"), "--no-contacts", "--json", str(tmp_path / "out.json"),
        "--html", str(tmp_path / "view.html"),
    ])  # fmt: skip
    assert args.func(args) == plan.EXIT_OK
    out = capsys.readouterr().out
    assert "waypoints[0] repaired" in out and "wall" in out and "plan succeeded" in out
    data = json.loads((tmp_path / "out.json").read_text())
    assert data["repairs"][0]["index"] == 0 and data["steps"] == []
    assert (tmp_path / "view.html").stat().st_size > 100_000


def test_mani_plan_bad_file_is_a_usage_error(tmp_path, capsys):
    (tmp_path / "bad.json").write_text(json.dumps({"robot": {"name": "allegro"}}))
    args = _parser().parse_args(["plan", str(tmp_path / "bad.json")])
    assert args.func(args) == plan.EXIT_USAGE
    assert "missing field(s)" in capsys.readouterr().out


def test_bench_plan_trajectory_table(capsys):
    args = _parser().parse_args(["bench", "plan", "--seeds", "0", "--waypoints", "3", "--obstacles", "4",
                                 "--no-contacts", "--time-limit", "3"])  # fmt: skip
    assert args.func(args) == bench_plan.EXIT_OK
    out = capsys.readouterr().out
    assert "plan bench" in out and "RRT segs" in out
