"""Generation: feasible grasps, seeded reproducible shards, manifest and resume, the training loader."""

from __future__ import annotations

import json
from dataclasses import asdict, replace
from pathlib import Path

import numpy as np
import pytest
import torch

from manifoundation.core.objects import make_object
from manifoundation.core.robots import get_hand
from research.data.checks import PENETRATION_TOL, ObjectField, self_overlap
from research.data.dataset import load_examples, make_batch
from research.data.generate import DataConfig, generate, object_split, run_shard
from research.data.ik import pad_spheres
from research.data.sampling import TIP_TOL, sample_grasps

CFG = DataConfig(
    objects=2,
    objects_per_shard=1,
    hands=("panda_gripper",),
    held_out_hands=(),
    palms=6,
    grasps_per_job=2,
    examples_per_grasp=2,
    num_points=256,
    test_fraction=0.5,
    kinds=("box", "sphere"),
)


def test_sampled_grasps_touch_without_collisions() -> None:
    hand = get_hand("panda_gripper")
    obj = make_object("box", 0.06, 0, num_points=256)
    field = ObjectField(obj.mesh)
    grasps = sample_grasps(hand, field, obj.size, np.random.default_rng(0), palms=8, max_grasps=3)
    assert grasps
    for g in grasps:
        pose = (torch.as_tensor(g.palm_pos[None]), torch.as_tensor(g.palm_quat[None]), torch.as_tensor(g.q[None]))
        pads, radii = pad_spheres(hand, *pose)
        assert np.all(np.abs(field.exact_signed_distance(pads[0]) - radii) <= TIP_TOL + 1e-9)
        assert np.all((g.q >= hand.lower - 1e-9) & (g.q <= hand.upper + 1e-9))
        assert self_overlap(hand, *pose)[0] <= PENETRATION_TOL
        assert g.penetration <= PENETRATION_TOL and g.self_overlap <= PENETRATION_TOL
        np.testing.assert_allclose(np.linalg.norm(g.normals, axis=1), 1.0, atol=1e-9)


def test_object_split_is_fixed_by_id() -> None:
    assert object_split("box-12345678", 0.2) == object_split("box-12345678", 0.2)
    splits = {object_split(f"box-{i:08x}", 0.3) for i in range(50)}
    assert splits == {"train", "test"}


def test_shards_are_reproducible_and_generation_resumes(tmp_path: Path) -> None:
    a, b = tmp_path / "a", tmp_path / "b"
    a.mkdir()
    b.mkdir()
    ra, rb = run_shard(CFG, 0, str(a)), run_shard(CFG, 0, str(b))
    assert ra.examples == rb.examples
    za, zb = np.load(a / ra.file), np.load(b / rb.file)
    for k in za.files:
        np.testing.assert_array_equal(za[k], zb[k])
    manifest = generate(CFG, tmp_path / "c", workers=1, progress=False)
    assert manifest["totals"]["shards"] == 2
    mtime = (tmp_path / "c" / "shard-00000.npz").stat().st_mtime_ns
    again = generate(CFG, tmp_path / "c", workers=1, progress=False)  # resume: nothing to do
    assert (tmp_path / "c" / "shard-00000.npz").stat().st_mtime_ns == mtime
    assert again["totals"] == manifest["totals"]
    saved = json.loads((tmp_path / "c" / "manifest.json").read_text())
    assert saved["config"] == CFG.to_dict()
    with pytest.raises(ValueError, match="another configuration"):
        generate(DataConfig(objects=3), tmp_path / "c", workers=1, progress=False)
    splits = [s for s in ("train", "test_so", "test_uo") if saved["totals"]["counts"].get(s)]
    ex = load_examples(tmp_path / "c", tuple(splits))
    batch = make_batch(ex, np.arange(min(2, len(ex))), 0.2, np.random.default_rng(0))
    assert batch.obj.xyz.shape[1:] == (256, 3) and batch.hand.shape[2] == 6
    assert float(batch.obj.xyz.abs().max()) <= 0.5 + 1e-5
    assert torch.isfinite(batch.force).all() and torch.isfinite(batch.obj.motion).all()


def test_test_objects_only_keeps_every_object_and_the_full_sets_test_examples(tmp_path: Path) -> None:
    full = replace(CFG, objects=3, objects_per_shard=3, test_fraction=0.3)  # objects 0, 1 train; 2 test
    only = replace(full, test_objects_only=True)
    (tmp_path / "f").mkdir()
    (tmp_path / "o").mkdir()
    rf, ro = run_shard(full, 0, str(tmp_path / "f")), run_shard(only, 0, str(tmp_path / "o"))
    zf, zo = np.load(tmp_path / "f" / rf.file), np.load(tmp_path / "o" / ro.file)
    np.testing.assert_array_equal(zf["object_ids"], zo["object_ids"])
    test_objects = np.flatnonzero(zo["object_split"] == "test")
    assert 0 < len(test_objects) < 3
    assert set(zo["obj_index"].tolist()) <= set(test_objects.tolist())
    same = np.isin(zf["obj_index"], test_objects)
    assert ro.examples == int(same.sum()) > 0 and rf.examples > ro.examples
    for key in ("split", "hand", "motion", "heat", "force_map", "contacts", "q"):
        np.testing.assert_array_equal(zf[key][same], zo[key])


def test_a_data_set_made_before_a_setting_existed_resumes(tmp_path: Path) -> None:
    shards = {str(k): asdict(run_shard(CFG, k, str(tmp_path))) for k in (0, 1)}
    old = {k: v for k, v in CFG.to_dict().items() if k != "test_objects_only"}
    (tmp_path / "manifest.json").write_text(json.dumps({"config": old, "shards": shards}))
    manifest = generate(CFG, tmp_path, workers=1, progress=False)  # nothing to do, no "another configuration"
    assert manifest["config"] == CFG.to_dict() and manifest["totals"]["shards"] == 2


def test_data_sets_of_different_set_sizes_load_together(tmp_path: Path) -> None:
    small, default = replace(CFG, objects=1, max_set=1), replace(CFG, objects=1)
    generate(small, tmp_path / "s", workers=1, progress=False)
    generate(default, tmp_path / "d", workers=1, progress=False)
    splits = ("train", "test_so", "test_uo")
    ex_s, ex_d = load_examples(tmp_path / "s", splits), load_examples(tmp_path / "d", splits)
    assert ex_s.extra["set_contacts"].shape[1] == 1 and ex_d.extra["set_contacts"].shape[1] == 32
    both = load_examples([tmp_path / "s", tmp_path / "d"], splits)
    assert both.extra["set_contacts"].shape[1] == 32
    np.testing.assert_array_equal(both.extra["set_contacts"][: len(ex_s), :1], ex_s.extra["set_contacts"])
    assert np.isnan(both.extra["set_contacts"][: len(ex_s), 1:]).all()
    assert (both.extra["set_count"][: len(ex_s)] == 1).all()
