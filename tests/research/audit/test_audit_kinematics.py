"""The audit's own hand models agree with facts read off the description files."""

from __future__ import annotations

import numpy as np
import pytest

from research.audit import load_hand, pose_matrix
from research.audit.urdf import rpy_matrix

IDENTITY = (np.zeros(3), np.array([1.0, 0.0, 0.0, 0.0]))


def _poses(hand_name: str, joints: dict[str, float]) -> dict[str, np.ndarray]:
    hand = load_hand(hand_name)
    q, missing, problems = hand.joint_values(list(joints), list(joints.values()))
    assert not missing and not problems
    return hand.link_poses(*IDENTITY, q)


@pytest.mark.parametrize("name", ["allegro", "leap", "shadow", "panda_gripper", "barrett", "kinova3f"])
def test_every_fingertip_has_geometry(name: str) -> None:
    hand = load_hand(name)
    # the real surfaces: LEAP's description draws visual meshes only; Allegro's tips and the Panda's fingers
    # collide as primitives drawn around their visual meshes, which the audit judges on
    expected_source = "visual" if name in ("leap", "allegro", "panda_gripper") else "collision"
    for tip in hand.spec.fingertips:
        assert tip in hand.links
        assert hand.links[tip].source == expected_source
        link = hand.links[tip]
        assert all(p.is_watertight or hulled for p, hulled in zip(link.pieces, link.hulled, strict=True))


def test_barrett_zero_pose_is_the_sum_of_joint_origins() -> None:
    poses = _poses("barrett", {"bh_j11": 0.0, "bh_j12": 0.0, "bh_j22": 0.0, "bh_j32": 0.0})
    # bh_j11 origin (0.025, 0, 0.075) + bh_j12 (0, 0.05, 0.012) + bh_j13 (0, 0, 0.07), no rotations before j13
    np.testing.assert_allclose(poses["bh_f1_distal"][:3, 3], [0.025, 0.05, 0.157], atol=1e-6)
    # finger 3: origin (0, -0.05, 0.087) turned by pi about z, then (0, 0, 0.07)
    np.testing.assert_allclose(poses["bh_f3_distal"][:3, 3], [0.0, -0.05, 0.157], atol=1e-6)


def test_barrett_spread_mirrors_fingers_one_and_two_and_distal_joints_follow() -> None:
    hand = load_hand("barrett")
    q, _, _ = hand.joint_values(["bh_j11", "bh_j12", "bh_j22", "bh_j32"], [0.5, 1.0, 1.0, 0.2])
    assert q["bh_j21"] == pytest.approx(0.5)  # <mimic joint="bh_j11" multiplier="1"> with the axis flipped
    assert q["bh_j13"] == pytest.approx(0.3442)
    poses = hand.link_poses(*IDENTITY, q)
    p1, p2 = poses["bh_f1_distal"][:3, 3], poses["bh_f2_distal"][:3, 3]
    np.testing.assert_allclose(p2, [-p1[0], p1[1], p1[2]], atol=1e-6)
    assert abs(p1[0] - 0.025) > 1e-3  # the spread really moved finger 1


def test_kinova_zero_pose_follows_its_tilted_origin() -> None:
    poses = _poses("kinova3f", {"k3f_j11": 0.0, "k3f_j21": 0.0, "k3f_j31": 0.0})
    # k3f_j11: origin (0, -0.03, 0.1), rpy (-0.35, 0, pi); the distal joint sits 0.044 up the proximal link
    expected = [0.0, -0.03 - 0.044 * np.sin(0.35), 0.1 + 0.044 * np.cos(0.35)]
    np.testing.assert_allclose(poses["k3f_f1_distal"][:3, 3], expected, atol=1e-6)


def test_panda_opening_of_four_centimetres_puts_the_fingers_eight_apart() -> None:
    hand = load_hand("panda_gripper")
    q, _, _ = hand.joint_values(["panda_finger_joint1"], [0.04])
    assert q["panda_finger_joint2"] == pytest.approx(0.04)  # <mimic joint="panda_finger_joint1"/>
    poses = hand.link_poses(*IDENTITY, q)
    left, right = poses["panda_leftfinger"][:3, 3], poses["panda_rightfinger"][:3, 3]
    np.testing.assert_allclose(left, [0, 0.04, 0.0584], atol=1e-6)
    np.testing.assert_allclose(right, [0, -0.04, 0.0584], atol=1e-6)
    # rubber pads: boxes 15.2 mm deep centred 7.58 mm from the finger frame: inner faces 0.04 mm inside
    pad = load_hand("panda_gripper", prefer="collision").links["panda_leftfinger"].pieces[3]
    inner = (np.asarray(pad.vertices) @ poses["panda_leftfinger"][:3, :3].T + left)[:, 1].min()
    assert inner == pytest.approx(0.04 + 7.58e-3 - 7.6e-3, abs=1e-6)


def test_shadow_coupling_is_read_from_the_tendon_and_fk_matches_the_body_offsets() -> None:
    hand = load_hand("shadow")
    couplings = {c.joint: c for c in hand.kinematics.couplings}
    assert set(couplings) == {f"robot0:{f}J0" for f in ("FF", "MF", "RF", "LF")}
    assert couplings["robot0:FFJ0"].source == "robot0:FFJ1"
    assert couplings["robot0:FFJ0"].multiplier == pytest.approx(0.00805 / 0.00705)
    free = [j for j in hand.kinematics.limits if not j.endswith("J0") or j.startswith("robot0:TH")]
    assert len(free) == 18
    values = dict.fromkeys(free, 0.0)
    poses = _poses("shadow", values)
    # ffknuckle (0.033, 0, 0.095), proximal 0.045 long, middle 0.025 long
    np.testing.assert_allclose(poses["robot0:ffdistal"][:3, 3], [0.033, 0.0, 0.165], atol=1e-9)
    values["robot0:FFJ2"] = np.pi / 2  # flexion about x: the finger then points along -y
    poses = _poses("shadow", values)
    np.testing.assert_allclose(poses["robot0:ffdistal"][:3, 3], [0.033, -0.07, 0.095], atol=1e-9)
    q, _, _ = hand.joint_values(["robot0:FFJ1"], [0.7])
    assert q["robot0:FFJ0"] == pytest.approx(0.7 * 0.00805 / 0.00705)


def test_allegro_pytorch_kinematics_agrees_with_a_plain_numpy_chain() -> None:
    hand = load_hand("allegro")
    rng = np.random.default_rng(3)
    limits = hand.kinematics.limits
    q = {j: float(rng.uniform(lo, hi)) for j, (lo, hi) in limits.items()}
    palm_T = hand.kinematics.palm_transforms(q)
    urdf = hand.kinematics.urdf  # type: ignore[attr-defined]
    mine = {"palm_link": np.eye(4)}
    pending = list(urdf.joints.values())
    while pending:
        j = pending.pop(0)
        if j.parent not in mine:
            pending.append(j)
            continue
        motion = np.eye(4)
        if j.type in ("revolute", "continuous"):
            axis, angle = j.axis, q[j.name]
            K = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
            motion[:3, :3] = np.eye(3) + np.sin(angle) * K + (1 - np.cos(angle)) * K @ K
        mine[j.child] = mine[j.parent] @ j.origin @ motion
    for link, T in mine.items():
        np.testing.assert_allclose(palm_T[link], T, atol=2e-6)


def test_world_pose_composes_the_palm_pose() -> None:
    hand = load_hand("kinova3f")
    q, _, _ = hand.joint_values(["k3f_j11", "k3f_j21", "k3f_j31"], [0.3, 0.4, 0.5])
    quat = np.array([0.9, 0.1, -0.3, 0.2])
    quat /= np.linalg.norm(quat)
    world = hand.link_poses(np.array([0.1, -0.2, 0.3]), quat, q)
    local = hand.link_poses(*IDENTITY, q)
    W = pose_matrix([0.1, -0.2, 0.3], quat)
    np.testing.assert_allclose(W[:3, :3] @ W[:3, :3].T, np.eye(3), atol=1e-12)
    for link in local:
        np.testing.assert_allclose(world[link], W @ local[link], atol=1e-12)
    np.testing.assert_allclose(rpy_matrix(np.array([0.0, 0.0, np.pi / 2])) @ [1, 0, 0], [0, 1, 0], atol=1e-12)
