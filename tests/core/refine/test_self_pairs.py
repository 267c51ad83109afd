"""The near self-collision pairs, checked against every sphere pair's gap measured in numpy."""

import numpy as np
import pytest
import torch

from manifoundation.core.refine.self_pairs import PAIR_REACH, near_pairs
from manifoundation.core.robots import get_hand


@pytest.mark.parametrize("name", ["leap", "allegro"])
def test_the_pairs_within_reach_in_the_hands_order_with_their_distances(name: str) -> None:
    hand = get_hand(name)
    pairs = np.asarray(hand.self_collision_pairs)
    radii = np.asarray(hand.sphere_radii)
    rng = np.random.default_rng(0)
    kept = 0
    for _ in range(20):
        q = rng.uniform(hand.lower, hand.upper)
        pose = (torch.zeros(1, 3, dtype=torch.float64), torch.tensor([[1.0, 0, 0, 0]], dtype=torch.float64),
                torch.as_tensor(q[None], dtype=torch.float64))  # fmt: skip
        with torch.no_grad():
            centres = hand.spheres(*pose, jacobian=False)[0][0].numpy()
        diff = centres[pairs[:, 0]] - centres[pairs[:, 1]]
        dist = np.linalg.norm(diff, axis=1)
        within = np.flatnonzero(dist - radii[pairs].sum(axis=1) < PAIR_REACH)
        rows, got_dist, got_dir = near_pairs(centres, radii, pairs)
        np.testing.assert_array_equal(rows, within)  # ascending: the step's rows keep the hand's order
        np.testing.assert_allclose(got_dist, dist[within], rtol=1e-14)
        np.testing.assert_allclose(got_dir, diff[within] / dist[within, None], rtol=1e-12, atol=1e-15)
        kept += len(rows)
    assert 0 < kept < 0.5 * 20 * len(pairs)  # most pairs are far at a pose, some are near


def test_no_pairs_and_coincident_centres():
    rows, dist, direction = near_pairs(np.zeros((2, 3)), np.full(2, 0.01), np.zeros((0, 2), dtype=np.int64))
    assert rows.shape == (0,) and dist.shape == (0,) and direction.shape == (0, 3)
    rows, dist, direction = near_pairs(np.zeros((2, 3)), np.full(2, 0.01), np.array([[0, 1]]))
    np.testing.assert_array_equal(rows, [0])
    assert dist[0] == 0.0 and np.all(direction == 0.0)
