"""Kinematics of every built-in hand: shapes, finite-difference Jacobians, known FK values, load time."""

from __future__ import annotations

import time

import numpy as np
import pytest
import torch

from manifoundation.core.robots import Hand, get_hand, list_hands, load_hand
from manifoundation.core.robots.registry import BUILTINS

D64 = torch.float64


def _random_state(hand: Hand, B: int, seed: int = 0) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
    g = np.random.default_rng(seed)
    pos = torch.as_tensor(g.normal(scale=0.1, size=(B, 3)), dtype=D64)
    quat = torch.as_tensor(g.normal(size=(B, 4)), dtype=D64)
    quat = quat / quat.norm(dim=-1, keepdim=True)
    q = torch.as_tensor(g.uniform(hand.lower, hand.upper, size=(B, hand.dof)), dtype=D64)
    return pos, quat, q


def _fd_jacobian(hand: Hand, fn, pos, quat, q, eps: float = 1e-6) -> torch.Tensor:  # type: ignore[no-untyped-def]
    """Central differences of ``fn`` through ``apply_delta``: (B, n, 3, 6 + D)."""
    B, n = pos.shape[0], fn(pos, quat, q).shape[1]
    cols = []
    for k in range(6 + hand.dof):
        d = torch.zeros(B, 6 + hand.dof, dtype=D64)
        d[:, k] = eps
        plus = fn(*hand.apply_delta(pos, quat, q, d))
        minus = fn(*hand.apply_delta(pos, quat, q, -d))
        cols.append((plus - minus) / (2 * eps))
    out = torch.stack(cols, dim=-1)
    assert out.shape == (B, n, 3, 6 + hand.dof)
    return out


@pytest.mark.parametrize("name", list_hands())
def test_builtin_loads_fast_and_has_consistent_shapes(name: str) -> None:
    # CPU time of this process: robust to other jobs sharing the machine (wall time equals it on an idle one)
    t0 = time.process_time()
    hand = BUILTINS[name]()  # uncached build
    _ = hand.surface_points
    elapsed = time.process_time() - t0
    assert elapsed < 2.0, f"{name} took {elapsed:.2f} s of CPU to build"
    D, m, S = hand.dof, hand.num_fingertips, len(hand.sphere_radii)
    assert len(hand.joint_names) == D and hand.lower.shape == hand.upper.shape == hand.rest.shape == (D,)
    assert np.all(hand.lower <= hand.rest) and np.all(hand.rest <= hand.upper)
    assert hand.tip_offsets.shape == (m, 3)
    assert hand.sphere_centres.shape == (S, 3) and len(hand.sphere_links) == S and np.all(hand.sphere_radii > 0)
    assert hand.self_collision_pairs.ndim == 2 and hand.self_collision_pairs.shape[1] == 2
    assert hand.surface_points.shape == hand.surface_normals.shape == (1024, 3)
    np.testing.assert_allclose(np.linalg.norm(hand.surface_normals, axis=1), 1.0, atol=1e-6)
    assert abs(np.linalg.norm(hand.approach_axis) - 1) < 1e-9
    assert set(hand.sphere_links) <= set(hand.collision_meshes)


@pytest.mark.parametrize("name", list_hands())
def test_jacobians_match_finite_differences(name: str) -> None:
    hand = get_hand(name)
    pos, quat, q = _random_state(hand, B=3)
    p, J = hand.fingertip_jacobians(pos, quat, q)
    np.testing.assert_allclose(p.numpy(), hand.fingertips(pos, quat, q).numpy())
    J_fd = _fd_jacobian(hand, hand.fingertips, pos, quat, q)
    assert float((J - J_fd).abs().max()) < 1e-6
    c, Jc = hand.spheres(pos, quat, q)
    Jc_fd = _fd_jacobian(hand, lambda p_, q_, j_: hand.spheres(p_, q_, j_, jacobian=False)[0], pos, quat, q)
    assert c.shape == (3, len(hand.sphere_radii), 3)
    assert float((Jc - Jc_fd).abs().max()) < 1e-6


@pytest.mark.parametrize("name", list_hands())
def test_float32_follows_inputs_and_link_poses(name: str) -> None:
    hand = get_hand(name)
    pos, quat, q = (t.float() for t in _random_state(hand, B=2))
    p, J = hand.fingertip_jacobians(pos, quat, q)
    assert p.dtype == J.dtype == torch.float32 and J.shape == (2, hand.num_fingertips, 3, 6 + hand.dof)
    poses = hand.link_poses(pos, quat, q)
    for link in hand.fingertip_links + list(hand.collision_meshes):
        assert poses[link].shape == (2, 4, 4)


def test_panda_gripper_fk_by_hand() -> None:
    """Hand-computed: fingers slide ±q along palm y at z = 58.4 mm; pads 45.25 mm further up."""
    hand = get_hand("panda_gripper")
    assert hand.joint_names == ["panda_finger_joint1"]
    # palm at (0.1, 0.2, 0.3), rotated 90° about z: palm y -> world -x
    pos = torch.tensor([[0.1, 0.2, 0.3]], dtype=D64)
    quat = torch.tensor([[np.cos(np.pi / 4), 0, 0, np.sin(np.pi / 4)]], dtype=D64)
    q = torch.tensor([[0.03]], dtype=D64)
    tips = hand.fingertips(pos, quat, q)[0].numpy()
    z = 0.3 + 0.0584 + 0.04525
    np.testing.assert_allclose(tips, [[0.1 - 0.03, 0.2, z], [0.1 + 0.03, 0.2, z]], atol=1e-12)
    poses = hand.link_poses(pos, quat, q)
    np.testing.assert_allclose(poses["panda_rightfinger"][0, :3, 3].numpy(), [0.13, 0.2, 0.3584], atol=1e-12)


def test_apply_delta_rotation_about_palm_origin() -> None:
    hand = get_hand("panda_gripper")
    pos, quat, q = _random_state(hand, B=1)
    delta = torch.zeros(1, 6 + hand.dof, dtype=D64)
    delta[0, 5] = np.pi / 2  # 90° about world z
    pos2, quat2, q2 = hand.apply_delta(pos, quat, q, delta)
    assert torch.equal(pos2, pos) and torch.equal(q2, q)
    before, after = hand.fingertips(pos, quat, q)[0], hand.fingertips(pos2, quat2, q2)[0]
    r = (before - pos).numpy()
    np.testing.assert_allclose((after - pos).numpy(), np.stack([-r[:, 1], r[:, 0], r[:, 2]], 1), atol=1e-12)


@pytest.mark.parametrize("name", list_hands())
def test_fingertips_lie_ahead_along_the_approach_axis(name: str) -> None:
    """At rest the fingertips sit in front of the palm origin along ``approach_axis`` (palm frame)."""
    hand = get_hand(name)
    pos, quat = torch.zeros(1, 3, dtype=D64), torch.tensor([[1.0, 0, 0, 0]], dtype=D64)
    tips = hand.fingertips(pos, quat, torch.as_tensor(hand.rest[None]))[0].numpy()
    assert float(tips.mean(0) @ hand.approach_axis) > 0.02


MIMIC_URDF = b"""<robot name="m"><link name="palm"><collision><geometry><box size="0.05 0.05 0.02"/></geometry>
</collision></link><link name="a"><collision><origin xyz="0 0 0.03"/><geometry><cylinder radius="0.008" length="0.06"/>
</geometry></collision></link><link name="b"><collision><origin xyz="0 0 0.02"/><geometry>
<box size="0.01 0.01 0.04"/></geometry></collision></link><link name="s"><collision><geometry>
<sphere radius="0.01"/></geometry></collision></link><link name="tip"/>
<joint name="ja" type="revolute"><parent link="palm"/><child link="a"/><origin xyz="0.02 0 0.01" rpy="0.1 0.2 0.3"/>
<axis xyz="0 1 0"/><limit lower="-1" upper="1"/></joint>
<joint name="jb" type="revolute"><parent link="a"/><child link="b"/><origin xyz="0 0 0.06"/><axis xyz="1 1 0"/>
<limit lower="-2" upper="2"/><mimic joint="ja" multiplier="-0.5" offset="0.3"/></joint>
<joint name="js" type="prismatic"><parent link="palm"/><child link="s"/><origin xyz="-0.02 0 0.01"/>
<axis xyz="0 0 1"/><limit lower="0" upper="0.05"/><mimic joint="ja" multiplier="0.02"/></joint>
<joint name="jt" type="fixed"><parent link="b"/><child link="tip"/><origin xyz="0 0.005 0.04" rpy="0 0.5 0"/></joint>
</robot>"""


def test_user_mimic_with_negative_multiplier_offset_and_prismatic() -> None:
    hand = load_hand(MIMIC_URDF, fingertips=["tip", "s"], tip_offsets=[[0.001, 0.002, 0.003], [0, 0, 0.01]])
    assert hand.joint_names == ["ja"]
    pos, quat, q = _random_state(hand, B=4, seed=5)
    J_fd = _fd_jacobian(hand, hand.fingertips, pos, quat, q)
    assert float((hand.fingertip_jacobians(pos, quat, q)[1] - J_fd).abs().max()) < 1e-6
    Jc_fd = _fd_jacobian(hand, lambda p_, q_, j_: hand.spheres(p_, q_, j_, jacobian=False)[0], pos, quat, q)
    assert float((hand.spheres(pos, quat, q)[1] - Jc_fd).abs().max()) < 1e-6
    # jb = -0.5 ja + 0.3 must stay in [-2, 2]; js = 0.02 ja in [0, 0.05] tightens ja to [0, 1]
    assert hand.lower[0] == pytest.approx(0.0) and hand.upper[0] == pytest.approx(1.0)
