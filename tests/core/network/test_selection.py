"""Contact selection by NMS: the mask is a hard constraint, at most H contacts, suppression radius."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from manifoundation.core.network import select_contacts


def grid(n: int = 400, seed: int = 0) -> np.ndarray:
    return np.random.default_rng(seed).random((n, 3))


def test_mask_is_hard_constraint() -> None:
    pts = grid()
    heat = np.zeros(len(pts))
    heat[pts[:, 0] < 0.5] = 1.0  # the network "wants" the left half
    mask = pts[:, 0] >= 0.5  # but only the right half is allowed
    heat[mask] = 0.6
    sel = select_contacts(pts, heat, np.ones((len(pts), 3)), mask, max_contacts=4)
    assert len(sel) == 4
    assert mask[sel.indices].all()


def test_everything_masked_gives_no_contact() -> None:
    pts = grid()
    sel = select_contacts(pts, np.ones(len(pts)), np.zeros((len(pts), 3)), np.zeros(len(pts), bool), 4)
    assert len(sel) == 0 and sel.points.shape == (0, 3) and sel.forces.shape == (0, 3)


def test_peaks_are_separated_and_ordered() -> None:
    pts = grid(800)
    centres = np.array([[0.2, 0.2, 0.2], [0.8, 0.8, 0.8], [0.2, 0.8, 0.5]])
    heat = np.exp(-(np.linalg.norm(pts[:, None] - centres[None], axis=-1) ** 2) / 0.02).max(axis=1)
    forces = np.arange(len(pts) * 3, dtype=float).reshape(-1, 3)
    sel = select_contacts(pts, heat, forces, None, max_contacts=5, radius=0.3, threshold=0.3)
    assert 1 <= len(sel) <= 5
    assert np.all(np.diff(sel.scores) <= 0)
    d = np.linalg.norm(sel.points[:, None] - sel.points[None], axis=-1) + np.eye(len(sel)) * 9
    assert d.min() > 0.3
    np.testing.assert_array_equal(sel.forces, forces[sel.indices])
    # the best contact is near one of the blob centres
    assert np.linalg.norm(centres - sel.points[0], axis=1).min() < 0.15


def test_isolated_spike_is_dropped() -> None:
    pts = grid(2000)
    pts[7] = [0.99, 0.99, 0.99]
    heat = np.zeros(len(pts))
    heat[7] = 1.0  # a lone spike, far from the blob
    blob = np.linalg.norm(pts - 0.2, axis=1) < 0.15
    heat[blob] = 0.8
    sel = select_contacts(pts, heat, np.zeros((len(pts), 3)), None, 2, radius=0.1, min_group_size=3)
    assert 7 not in sel.indices.tolist()
    assert len(sel) >= 1 and blob[sel.indices].all()


def test_low_but_peaked_heatmap_selects_its_peaks() -> None:
    pts = grid(800)
    centres = np.array([[0.2, 0.2, 0.2], [0.8, 0.8, 0.8]])
    pts[:2] = centres
    blobs = np.exp(-(np.linalg.norm(pts[:, None] - centres[None], axis=-1) ** 2) / 0.04).max(axis=1)
    heat = 0.3 * blobs  # the right places, but under the absolute threshold 0.5
    zeros = np.zeros((len(pts), 3))
    assert len(select_contacts(pts, heat, zeros, None, 4, relative=None)) == 0
    sel = select_contacts(pts, heat, zeros, None, 4, radius=0.3)
    assert len(sel) == 2
    assert np.sort(np.linalg.norm(sel.points[:, None] - centres[None], axis=-1).min(axis=1)).max() < 0.1
    # a flat heatmap (an untrained network sits at its prior) selects nothing, whatever its level
    for level in (0.02, 0.2, 0.45):
        noisy = level + 0.01 * np.random.default_rng(1).random(len(pts))
        assert len(select_contacts(pts, noisy, zeros, None, 4)) == 0


def test_bad_shapes_raise() -> None:
    with pytest.raises(ValueError, match="heatmap"):
        select_contacts(grid(10), np.ones(9), np.ones((10, 3)), None, 2)


@settings(max_examples=30, deadline=None)
@given(
    seed=st.integers(0, 10_000),
    h=st.integers(0, 5),
    threshold=st.floats(0.0, 0.9),
    min_group=st.integers(1, 4),
)
def test_selection_invariants(seed: int, h: int, threshold: float, min_group: int) -> None:
    rng = np.random.default_rng(seed)
    pts, heat = rng.random((200, 3)), rng.random(200)
    mask = rng.random(200) > 0.5
    forces = rng.random((200, 3))
    sel = select_contacts(pts, heat, forces, mask, h, threshold=threshold, relative=None, min_group_size=min_group)
    assert len(sel) <= h
    assert mask[sel.indices].all()
    assert (heat[sel.indices] >= threshold).all()
    rel = select_contacts(pts, heat * threshold, forces, mask, h, min_group_size=min_group)  # peak ≤ threshold
    assert len(rel) <= h and mask[rel.indices].all()
    if len(rel):  # every contact at least halfway from the median to the peak
        scaled = heat[mask] * threshold
        tau = np.median(scaled) + 0.5 * (scaled.max() - np.median(scaled))
        assert (heat[rel.indices] * threshold >= min(tau, 0.5) - 1e-12).all()
    assert len(set(sel.indices.tolist())) == len(sel)
