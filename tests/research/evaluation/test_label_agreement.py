"""`research.evaluation.label_agreement`: regions from grasps that can produce a wrench, and the agreement figures."""

from __future__ import annotations

import numpy as np
import trimesh

from research.evaluation.label_agreement import independent_region, label_agreement


def _box() -> tuple[np.ndarray, np.ndarray]:
    mesh = trimesh.creation.box(extents=[0.1, 0.1, 0.1])
    points, faces = trimesh.sample.sample_surface(mesh, 2000, seed=0)
    return np.asarray(points), np.asarray(mesh.face_normals[faces])


def test_region_comes_from_the_grasps_that_can_produce_the_wrench() -> None:
    """An upward force through the centre: three contacts under the box can push it up, three on its top cannot;
    the region marks points near the first and none near the second."""
    points, normals = _box()
    corners = np.array([[0.03, 0.0], [-0.015, 0.026], [-0.015, -0.026]])
    below = np.c_[corners, np.full(3, -0.05)], np.tile([0.0, 0.0, -1.0], (3, 1))
    above = np.c_[corners, np.full(3, 0.05)], np.tile([0.0, 0.0, 1.0], (3, 1))
    lift = np.array([0.0, 0.0, 1.0, 0.0, 0.0, 0.0])
    centre, length = np.zeros(3), 0.1
    region, count = independent_region(points, normals, [above, below], 0.5, lift, centre, length)
    assert count == 1
    near_below = np.linalg.norm(points[:, None] - below[0][None], axis=-1).min(axis=1) < 0.005
    near_above = np.linalg.norm(points[:, None] - above[0][None], axis=-1).min(axis=1) < 0.005
    assert region[near_below].all() and not region[near_above].any()
    assert not region[points[:, 2] > 0.049].any()  # nothing on the top face
    none, zero = independent_region(points, normals, [above], 0.5, lift, centre, length)
    assert zero == 0 and not none.any()


def test_agreement_figures_on_known_regions() -> None:
    """Two cases of four points, three label sources each; the figures by hand."""
    first = np.array([[1, 1, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0]], dtype=bool)  # the data's, then two re-samplings
    second = np.array([[0, 0, 0, 1], [0, 0, 0, 1], [0, 0, 0, 1]], dtype=bool)
    report = label_agreement([first, second], [np.array([2, 0]), np.array([3, 3])])
    np.testing.assert_allclose(report.coverage, [(0.5 + 0.25) / 2, 0.25, (0.25 + 0.25) / 2])
    np.testing.assert_allclose(report.top_hit, [(0.5 + 1.0) / 2, (0.0 + 1.0) / 2, (0.5 + 1.0) / 2])
    assert report.union_coverage == (0.75 + 0.25) / 2 and report.union_top_hit == 1.0
    # the unions of the first 1, 2, 3 sources: first [1,1,0,0], [1,1,0,0], [1,1,1,0]; second [0,0,0,1] each
    np.testing.assert_allclose(report.denser_coverage, [(0.5 + 0.25) / 2, (0.5 + 0.25) / 2, (0.75 + 0.25) / 2])
    np.testing.assert_allclose(report.denser_top_hit, [(0.5 + 1.0) / 2, (0.5 + 1.0) / 2, 1.0])
    # pairs (j, k): how much of k's region lies in j's. first: (0,1) 1, (0,2) 0, (1,0) 1/2, (1,2) 0, (2,0) 0,
    # (2,1) 0; second: all six 1
    assert report.oracle_pair == (1.5 + 6) / 12
    # held out j, the points the other two mark most: first j=0: {1, 2} → 1/2, j=1: {0, 1, 2} → 1/3, j=2: {1}
    # → 0; second: {3} → 1 each
    assert np.isclose(report.oracle_held_out, (0.5 + 1 / 3 + 0.0 + 3.0) / 6)
