"""The compiled one-pose kinematics (`manifoundation.core.robots.kinematics_kernels`) against the batched torch code and
against finite differences, for every built-in hand."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from manifoundation.core.robots import get_hand, list_hands

D64 = torch.float64


def _poses(hand, seed: int) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:  # type: ignore[no-untyped-def]
    """Two random poses (B = 2; the quaternion left unnormalised: both paths normalise it)."""
    g = np.random.default_rng(seed)
    pos = torch.as_tensor(g.normal(scale=0.1, size=(2, 3)), dtype=D64)
    quat = torch.as_tensor(g.normal(size=(2, 4)), dtype=D64)
    q = torch.as_tensor(g.uniform(hand.lower, hand.upper, size=(2, hand.dof)), dtype=D64)
    return pos, quat, q


@pytest.mark.parametrize("name", list_hands())
def test_one_pose_matches_the_batched_torch_code(name: str) -> None:
    hand = get_hand(name)
    tree = hand.tree
    pos, quat, q = _poses(hand, seed=7)
    batched = tree.body_poses(pos, quat, q)  # B = 2: the torch code
    for b in range(2):
        one = tree.body_poses(pos[b : b + 1], quat[b : b + 1], q[b : b + 1])  # B = 1: the compiled path
        assert one.shape == (1, *batched.shape[1:]) and one.dtype == D64
        np.testing.assert_allclose(one[0].numpy(), batched[b].numpy(), rtol=0, atol=1e-13)
    g = np.random.default_rng(8)
    nb = batched.shape[1]
    bodies = g.integers(0, nb, size=40)
    points = torch.as_tensor(g.normal(scale=0.1, size=(2, 40, 3)), dtype=D64)
    jac = tree.point_jacobian(batched, bodies, points, pos)
    for b in range(2):
        one = tree.point_jacobian(batched[b : b + 1], bodies, points[b : b + 1], pos[b : b + 1])
        np.testing.assert_allclose(one[0].numpy(), jac[b].numpy(), rtol=0, atol=1e-13)


@pytest.mark.parametrize("name", ["leap", "allegro", "panda_gripper", "barrett"])
def test_one_pose_jacobians_match_finite_differences(name: str) -> None:
    hand = get_hand(name)
    pos, quat, q = (t[:1] for t in _poses(hand, seed=9))
    quat = quat / quat.norm(dim=-1, keepdim=True)
    _, jac = hand.fingertip_jacobians(pos, quat, q)
    eps, cols = 1e-6, []
    for k in range(6 + hand.dof):
        d = torch.zeros(1, 6 + hand.dof, dtype=D64)
        d[0, k] = eps
        plus = hand.fingertips(*hand.apply_delta(pos, quat, q, d))
        minus = hand.fingertips(*hand.apply_delta(pos, quat, q, -d))
        cols.append((plus - minus) / (2 * eps))
    assert float((jac - torch.stack(cols, dim=-1)).abs().max()) < 1e-6


def test_gradients_keep_the_torch_code() -> None:
    hand = get_hand("allegro")
    pos, quat, q = (t[:1].clone() for t in _poses(hand, seed=10))
    q.requires_grad_(True)
    poses = hand.tree.body_poses(pos, quat, q)
    poses[..., :3, 3].sum().backward()
    assert q.grad is not None and float(q.grad.abs().sum()) > 0


@pytest.mark.parametrize("name", ["leap", "allegro"])
def test_one_pose_step_matches_the_batched_torch_code(name: str) -> None:
    hand = get_hand(name)
    pos, quat, q = _poses(hand, seed=11)
    quat = quat / quat.norm(dim=-1, keepdim=True)
    g = np.random.default_rng(12)
    delta = torch.as_tensor(g.normal(scale=0.05, size=(2, 6 + hand.dof)), dtype=D64)
    delta[1, 3:6] = 1e-10  # the rotation's series branch
    batched = hand.apply_delta(pos, quat, q, delta)
    for b in range(2):
        one = hand.apply_delta(pos[b : b + 1], quat[b : b + 1], q[b : b + 1], delta[b : b + 1])
        for got, want in zip(one, batched, strict=True):
            assert got.shape == (1, *want.shape[1:])
            np.testing.assert_allclose(got[0].numpy(), want[b].numpy(), rtol=0, atol=1e-15)


@pytest.mark.parametrize("name", ["leap", "allegro"])
def test_one_pose_surface_samples_match_the_batched_torch_code(name: str) -> None:
    hand = get_hand(name)
    pos, quat, q = _poses(hand, seed=13)
    batched = hand.surface_samples(pos, quat, q, jacobian=False)
    some = np.arange(0, len(hand.contact_surface.body), 7)
    picked = hand.surface_samples(pos, quat, q, index=some, jacobian=False)
    for b in range(2):
        one = hand.surface_samples(pos[b : b + 1], quat[b : b + 1], q[b : b + 1], jacobian=False)
        for got, want in zip(one[:2], batched[:2], strict=True):
            np.testing.assert_allclose(got[0].numpy(), want[b].numpy(), rtol=0, atol=1e-15)
        one_picked = hand.surface_samples(pos[b : b + 1], quat[b : b + 1], q[b : b + 1], index=some, jacobian=False)
        np.testing.assert_allclose(one_picked[0][0].numpy(), picked[0][b].numpy(), rtol=0, atol=1e-15)
