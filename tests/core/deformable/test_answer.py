"""The deformable answer: its fallback (the points the task moves most, spread apart), the motion at a network
contact, and a slid body's contacts on both sides of its centre line."""

from __future__ import annotations

import numpy as np

from manifoundation.core.deformable.answer import deformable_contacts, is_slide, moving_indices


def _line(n: int = 101) -> np.ndarray:
    return np.stack([np.linspace(0.0, 1.0, n), np.zeros(n), np.zeros(n)], axis=1)


def test_the_most_moved_point_comes_first_and_the_second_is_not_its_neighbour() -> None:
    points = _line()
    motion = np.zeros_like(points)
    motion[:, 2] = np.exp(-(((points[:, 0] - 0.3) / 0.05) ** 2)) + 0.9 * np.exp(-(((points[:, 0] - 0.8) / 0.05) ** 2))
    picked = moving_indices(points, np.arange(len(points)), motion, 2)
    assert picked[0] == 30  # the peak of the larger bump
    assert abs(points[picked[1], 0] - 0.8) < 0.03  # the other bump's peak, not a point beside the first


def test_an_equal_motion_everywhere_is_farthest_point_sampling() -> None:
    points = _line()
    motion = np.tile([0.0, 0.0, 0.1], (len(points), 1))
    picked = moving_indices(points, np.arange(len(points)), motion, 3)
    assert picked[0] == 0 and set(picked[1:]) == {100, 50}


def test_only_allowed_points_are_taken_and_a_later_proposal_may_start_elsewhere() -> None:
    points = _line()
    motion = np.zeros_like(points)
    motion[:, 2] = points[:, 0]  # the far end moves most
    allowed = np.arange(0, 60)
    picked = moving_indices(points, allowed, motion, 2)
    assert set(picked) <= set(allowed) and picked[0] == 59
    starts = {int(moving_indices(points, allowed, motion, 2, np.random.default_rng(s))[0]) for s in range(20)}
    assert len(starts) > 1 and all(motion[i, 2] >= 0.8 * motion[59, 2] for i in starts)


def test_a_flat_heatmap_falls_back_to_the_moving_points_with_their_motion() -> None:
    points = _line()
    motion = np.zeros_like(points)
    motion[95:, 1] = 0.2
    flat = np.full(len(points), 0.02)
    answer = deformable_contacts(points, flat, motion, None, 1)
    assert answer.source == "motion_fallback"
    assert answer.indices[0] >= 95
    np.testing.assert_array_equal(answer.motions, motion[answer.indices])


def test_a_network_contact_moves_by_the_targets_displacement_there() -> None:
    """The heatmap places the contact; its motion is the task's own at that point (a grasped point ends where the
    target says), not a motion map's estimate of it."""
    points = _line()
    motion = np.zeros_like(points)
    motion[:, 1] = 0.1 * points[:, 0]  # a turn about the first point: each point's own displacement
    heat = np.full(len(points), 0.02)
    heat[68:73] = [0.5, 0.8, 0.9, 0.8, 0.5]
    answer = deformable_contacts(points, heat, motion, None, 1)
    assert answer.source == "network" and answer.indices[0] == 70
    np.testing.assert_array_equal(answer.motions, motion[[70]])


def _square(n: int = 41) -> np.ndarray:
    """(n², 3) a flat 1 × 1 square at the table's height, centred on the origin."""
    u = np.linspace(-0.5, 0.5, n)
    x, y = np.meshgrid(u, u, indexing="ij")
    return np.stack([x.ravel(), y.ravel(), np.zeros(n * n)], axis=1)


def _bumps(points: np.ndarray, centres: list[tuple[float, float]], heights: list[float]) -> np.ndarray:
    heat = np.full(len(points), 0.01)
    for (cx, cy), h in zip(centres, heights, strict=True):
        heat = np.maximum(heat, h * np.exp(-((points[:, 0] - cx) ** 2 + (points[:, 1] - cy) ** 2) / (2 * 0.03**2)))
    return heat


def test_a_slid_body_is_taken_on_both_sides_of_the_line_along_its_motion() -> None:
    # slid along +x: the two highest peaks sit on the left edge's front (y > 0); the third on the right front
    points = _square()
    peaks = [(0.45, 0.45), (0.3, 0.45), (0.45, -0.4)]
    heat = _bumps(points, peaks, [0.9, 0.85, 0.8])
    d = np.array([0.2, 0.0, 0.0])
    slide = np.tile(d, (len(points), 1))
    answer = deformable_contacts(points, heat, slide, None, 2)
    got = sorted(map(tuple, np.round(answer.points[:, :2], 2)))
    assert answer.source == "network" and got == sorted([peaks[0], peaks[2]])
    np.testing.assert_allclose(answer.motions, np.tile(d, (2, 1)))
    # the same maps for a fold (the motion grows along x): the plain NMS order, the two highest peaks
    fold = np.zeros_like(points)
    fold[:, 2] = 0.2 * (points[:, 0] + 0.5)
    answer = deformable_contacts(points, heat, fold, None, 2)
    assert sorted(map(tuple, np.round(answer.points[:, :2], 2))) == sorted(peaks[:2])


def test_a_slide_is_a_motion_alike_everywhere() -> None:
    points = _square(11)
    d = np.array([0.1, -0.05, 0.0])
    assert is_slide(np.tile(d, (len(points), 1)))
    assert is_slide(np.tile(d, (len(points), 1)) + 0.005 * np.random.default_rng(0).standard_normal((len(points), 3)))
    assert not is_slide(np.zeros_like(points))
    rotation = np.cross([0.0, 0.0, 0.1], points)  # a turn about the centre: no two points move alike
    assert not is_slide(rotation) and not is_slide(rotation + d)
