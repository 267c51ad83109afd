"""Opposed contact sets on shapes whose opposite faces are known."""

from __future__ import annotations

import numpy as np
import trimesh

from manifoundation.core.geometry.opposition import opposed_contacts


def _box(extents: tuple[float, float, float], count: int = 3000) -> tuple[np.ndarray, np.ndarray]:
    box = trimesh.creation.box(extents=extents)
    pts, face = trimesh.sample.sample_surface_even(box, count, seed=0)
    return np.asarray(pts), np.asarray(box.face_normals[face])


def test_a_pair_on_a_box_lies_on_opposite_faces_across_its_width() -> None:
    pts, nrm = _box((0.03, 0.06, 0.08))
    sets = opposed_contacts(pts, nrm, 2, 0.0, 0.05, 5, np.random.default_rng(0))
    assert len(sets) == 5 and len({int(s.indices[0]) for s in sets}) == 5  # distinct thumb points
    for s in sets:
        a, b = s.indices
        assert nrm[a] @ nrm[b] < -0.99  # opposite faces
        assert abs(abs(nrm[a][0]) - 1) < 1e-9  # only the 3 cm faces are within the 5 cm opening
        assert abs(s.width - 0.03) < 0.004 and s.imbalance < 0.01


def test_nothing_opposed_within_the_opening_gives_no_sets() -> None:
    pts, nrm = _box((0.06, 0.06, 0.08))
    assert opposed_contacts(pts, nrm, 2, 0.0, 0.05, 3, np.random.default_rng(0)) == []


def test_a_thumb_and_three_fingers_lie_in_a_row_facing_it() -> None:
    pts, nrm = _box((0.03, 0.1, 0.1))
    for s in opposed_contacts(pts, nrm, 4, 0.02, 0.05, 4, np.random.default_rng(1)):
        thumb, fingers = s.indices[0], s.indices[1:]
        assert len(set(fingers.tolist())) == 3
        assert np.all(nrm[fingers] @ nrm[thumb] < -0.99)
        row = pts[fingers] - pts[fingers].mean(axis=0)
        assert np.linalg.svd(row, compute_uv=False)[1] < 0.004  # nearly a line
        gaps = np.sort(np.linalg.norm(pts[fingers][:, None] - pts[fingers][None], axis=2), axis=1)[:, 1]
        assert np.all((gaps > 0.008) & (gaps < 0.024))  # the finger spacing, or at least half of it
        # the row is centred on the point facing the thumb: no net torque from equal pushes
        assert np.linalg.norm(np.cross(pts[fingers].mean(axis=0) - pts[thumb], nrm[thumb])) < 0.005


def test_the_weight_steers_the_draw() -> None:
    pts, nrm = _box((0.03, 0.06, 0.08))
    weight = (pts[:, 2] > 0.03).astype(float)  # prefer the top of the box
    sets = opposed_contacts(pts, nrm, 2, 0.0, 0.05, 10, np.random.default_rng(0), weight=weight)
    assert np.mean([pts[s.indices, 2].mean() > 0.03 for s in sets]) >= 0.8
