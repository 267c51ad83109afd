"""Cross-checks: our FK against pytorch-kinematics, mimic/coupled joints, and the packaged hull cache."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import pytorch_kinematics as pk
import torch

from manifoundation.core.robots import get_hand
from manifoundation.core.robots.meshcache import build_hull_cache
from manifoundation.core.robots.registry import DESCRIPTIONS, _erd, _site_packages

D64 = torch.float64
IDENTITY = (torch.zeros(1, 3, dtype=D64), torch.tensor([[1.0, 0, 0, 0]], dtype=D64))


@pytest.mark.parametrize(
    "name, path",
    [
        ("allegro", _erd("allegro_hand_description", "urdf", "allegro_right_hand.urdf")),
        ("barrett", DESCRIPTIONS / "barrett_bh8.urdf"),
    ],
)
def test_fk_matches_pytorch_kinematics(name: str, path: Path) -> None:
    hand = get_hand(name)
    chain = pk.build_chain_from_urdf(path.read_bytes()).to(dtype=D64)
    g = np.random.default_rng(3)
    q = g.uniform(hand.lower, hand.upper, size=(4, hand.dof))
    # expand our free joints to pk's joint list (mimic joints follow their source)
    values = {}
    for jn in chain.get_joint_parameter_names():
        if jn in hand.joint_names:
            values[jn] = q[:, hand.joint_names.index(jn)]
    mimic = {"bh_j21": ("bh_j11", 1.0), "bh_j13": ("bh_j12", 0.3442), "bh_j23": ("bh_j22", 0.3442)}
    mimic["bh_j33"] = ("bh_j32", 0.3442)
    for jn, (src, m) in mimic.items():
        if jn in chain.get_joint_parameter_names():
            values[jn] = m * q[:, hand.joint_names.index(src)]
    th = torch.as_tensor(np.stack([values[jn] for jn in chain.get_joint_parameter_names()], 1), dtype=D64)
    ref = chain.forward_kinematics(th)
    ours = hand.link_poses(IDENTITY[0].expand(4, 3), IDENTITY[1].expand(4, 4), torch.as_tensor(q))
    for link in hand.collision_meshes:
        np.testing.assert_allclose(
            ours[link].numpy(), ref[link].get_matrix().numpy(), rtol=0, atol=1e-6
        )  # pk keeps URDF origins in float32


def test_panda_mimic_finger_mirrors() -> None:
    hand = get_hand("panda_gripper")
    poses = hand.link_poses(*IDENTITY, torch.tensor([[0.025]], dtype=D64))
    assert poses["panda_leftfinger"][0, 1, 3] == pytest.approx(0.025)
    assert poses["panda_rightfinger"][0, 1, 3] == pytest.approx(-0.025)


def test_shadow_distal_joint_is_tied_to_middle() -> None:
    hand = get_hand("shadow")
    assert hand.dof == 18 and "robot0:FFJ0" not in hand.joint_names and "robot0:THJ0" in hand.joint_names
    assert hand.upper[hand.joint_names.index("robot0:FFJ1")] == pytest.approx(1.571 * 0.00705 / 0.00805)
    q = torch.as_tensor(hand.rest[None]).clone()
    q[0, hand.joint_names.index("robot0:FFJ1")] = 0.7
    poses = hand.link_poses(*IDENTITY, q)
    rel = torch.linalg.inv(poses["robot0:ffmiddle"][0]) @ poses["robot0:ffdistal"][0]
    angle = float(torch.atan2(rel[2, 1], rel[1, 1]))  # rotation about x
    assert angle == pytest.approx(0.7 * 0.00805 / 0.00705, abs=1e-9)


def test_leap_hull_cache_regenerates_identically(tmp_path: Path) -> None:
    out = tmp_path / "leap_hulls.npz"
    build_hull_cache(_site_packages() / "ghand" / "assets" / "models" / "meshes", out)
    new, old = np.load(out), np.load(DESCRIPTIONS / "leap_hulls.npz")
    assert sorted(new.files) == sorted(old.files)
    for k in new.files:
        np.testing.assert_array_equal(new[k], old[k])
