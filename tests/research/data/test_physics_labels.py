"""Labels from grasps that hold: the physics filter keeps a grasp that holds and drops one that does not, and a shard
made with ``physics: closure`` labels only with grasps that held."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import trimesh

from manifoundation.core.robots import get_hand
from research.data.generate import DataConfig, run_shard
from research.data.physics_labels import held_grasps
from research.data.sampling import Grasp

PAD_Z, HALF = 0.1, 0.02  # the Panda's pads sit at y = ±q, z 0.06-0.11 in the palm frame; the box's ±y faces at ±2 cm


def _grasp(q: float, contact_y: float) -> Grasp:
    contacts = np.array([[0.0, contact_y, PAD_Z], [0.0, -contact_y, PAD_Z]])
    normals = np.array([[0.0, 1.0, 0.0], [0.0, -1.0, 0.0]])
    return Grasp(np.zeros(3), np.array([1.0, 0.0, 0.0, 0.0]), np.array([q]), contacts, normals, 0.0, 0.0)


def test_a_grasp_that_holds_is_kept_and_one_that_does_not_is_dropped() -> None:
    box = trimesh.creation.box(extents=[0.03, 2 * HALF, 0.03])
    box.apply_translation([0.0, 0.0, PAD_Z])
    on_faces = _grasp(HALF, HALF)  # both pads on the box's faces: the squeeze holds it
    open_wide = _grasp(0.04, HALF)  # pads 2 cm off each face: the 1 cm squeeze never reaches it
    judged = held_grasps(get_hand("panda_gripper"), [open_wide, on_faces], box)
    assert [r.success for r in judged.results] == [False, True]
    assert judged.held == [on_faces]


def test_a_shard_with_physics_labels_only_grasps_that_held(tmp_path: Path) -> None:
    cfg = DataConfig(objects=1, objects_per_shard=1, hands=("panda_gripper",), held_out_hands=(), palms=6,
                     grasps_per_job=3, examples_per_grasp=1, num_points=256, kinds=("box",))  # fmt: skip
    (tmp_path / "off").mkdir()
    (tmp_path / "on").mkdir()
    off = run_shard(cfg, 0, str(tmp_path / "off"))
    on = run_shard(replace(cfg, physics="closure"), 0, str(tmp_path / "on"))
    tested, held = on.counts["physics/tested/panda_gripper"], on.counts.get("physics/held/panda_gripper", 0)
    assert tested > 0 and 0 <= held <= tested
    assert "physics/tested/panda_gripper" not in off.counts
    assert on.examples <= off.examples and (held > 0 or on.examples == 0)


def test_closure_sampling_reaches_the_sampler(tmp_path: Path) -> None:
    """``closure_mu`` samples pinching palms: on an 8 cm box (seed 3's first object) the Panda's grasps are then
    found and tested."""
    cfg = DataConfig(objects=1, objects_per_shard=1, hands=("panda_gripper",), held_out_hands=(), palms=6,
                     grasps_per_job=3, examples_per_grasp=1, num_points=256, kinds=("box",), physics="closure",
                     closure_mu=0.6, seed=3)  # fmt: skip
    result = run_shard(cfg, 0, str(tmp_path))
    assert result.counts["physics/tested/panda_gripper"] > 0
