"""`separate`: its step is the damped least squares over every pad row and every overlapping pair's row."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from manifoundation.core.robots import get_hand
from research.data.ik import CONTACT_STANDOFF, DAMPING, MAX_JOINT_STEP, _points_and_jacobian, separate, tip_points

RADIUS = 0.05


def sphere_surface(p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Nearest points and outward normals on a sphere of radius ``RADIUS`` about the origin."""
    n = p / np.linalg.norm(p, axis=1, keepdims=True)
    return RADIUS * n, n


def overlapping_poses(hand_name: str, count: int) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
    """``count`` random joint configurations with at least one self-collision pair overlapping."""
    hand = get_hand(hand_name)
    rng = np.random.default_rng(0)
    q = torch.as_tensor(rng.uniform(hand.lower, hand.upper, (20 * count, hand.dof)))
    pos = torch.tensor([[0.0, 0.0, 0.12]], dtype=torch.float64).expand(len(q), 3).contiguous()
    quat = torch.tensor([[0.0, 1.0, 0.0, 0.0]], dtype=torch.float64).expand(len(q), 4).contiguous()
    c, _ = hand.spheres(pos, quat, q, jacobian=False)
    pairs = torch.as_tensor(np.asarray(hand.self_collision_pairs).reshape(-1, 2))
    radii = torch.as_tensor(hand.sphere_radii, dtype=torch.float64)
    over = radii[pairs].sum(1) - (c[:, pairs[:, 0]] - c[:, pairs[:, 1]]).norm(dim=-1)
    rows = torch.nonzero((over > 0).any(dim=1)).flatten()[:count]
    assert len(rows) == count
    return pos[rows], quat[rows], q[rows]


def dense_step(hand_name: str, pos: torch.Tensor, quat: torch.Tensor, q: torch.Tensor) -> torch.Tensor:
    """One step written out with every pair's row stacked (zero where the pair does not overlap)."""
    hand = get_hand(hand_name)
    margin = 2e-3
    pairs = torch.as_tensor(np.asarray(hand.self_collision_pairs).reshape(-1, 2))
    radii = torch.as_tensor(hand.sphere_radii, dtype=torch.float64)
    c, jc = hand.spheres(pos, quat, q)
    diff = c[:, pairs[:, 0]] - c[:, pairs[:, 1]]
    over = radii[pairs].sum(1) + margin - diff.norm(dim=-1)
    bodies, _, pad_np, radii_np = tip_points(hand)
    pads, jt = _points_and_jacobian(hand, pos, quat, q, bodies, torch.as_tensor(pad_np, dtype=torch.float64))
    near, nrm = sphere_surface(pads.reshape(-1, 3).numpy())
    goal = torch.as_tensor(near + np.tile(radii_np + CONTACT_STANDOFF, len(q))[:, None] * nrm).reshape(pads.shape)
    u = diff / diff.norm(dim=-1, keepdim=True)
    active = (over > 0).to(torch.float64)
    rows_p = (u[..., None] * (jc[:, pairs[:, 0], :, 6:] - jc[:, pairs[:, 1], :, 6:])).sum(2) * active[..., None]
    J = torch.cat([jt[..., 6:].reshape(len(q), -1, hand.dof), rows_p], dim=1)
    e = torch.cat([(goal - pads).reshape(len(q), -1), over.clamp_min(0) * active], dim=1)
    A = J.transpose(1, 2) @ J + DAMPING**2 * torch.eye(hand.dof, dtype=torch.float64)
    dq = torch.linalg.solve(A, J.transpose(1, 2) @ e[..., None])[..., 0].clamp(-MAX_JOINT_STEP, MAX_JOINT_STEP)
    lower, upper = torch.as_tensor(hand.lower), torch.as_tensor(hand.upper)
    return torch.minimum(torch.maximum(q + dq, lower), upper)


@pytest.mark.parametrize("hand_name", ["allegro", "leap"])
def test_one_step_equals_the_dense_least_squares(hand_name: str) -> None:
    pos, quat, q = overlapping_poses(hand_name, 6)
    got = separate(get_hand(hand_name), pos, quat, q, sphere_surface, iters=1)
    want = dense_step(hand_name, pos, quat, q)
    assert not torch.allclose(got, q)
    torch.testing.assert_close(got, want, rtol=0, atol=1e-10)
