"""The audit's ray-parity inside test agrees with analytic solids, also on axis-aligned, grid-like queries."""

from __future__ import annotations

import numpy as np
import trimesh

from research.audit import concave_test_shapes
from research.audit.inside import InsideTest


def _queries(bounds: np.ndarray, n: int = 6000) -> np.ndarray:
    rng = np.random.default_rng(1)
    pts = rng.uniform(bounds[0] - 0.003, bounds[1] + 0.003, (n, 3))
    pts[: n // 4] = np.round(pts[: n // 4], 3)  # on a millimetre grid: aligned with the shapes' edges and faces
    return pts


def test_box_and_l_shape_match_their_analytic_interiors() -> None:
    box = trimesh.creation.box(extents=[0.04, 0.06, 0.02])
    pts = _queries(box.bounds)
    half = np.array([0.02, 0.03, 0.01])
    gap = np.abs(np.abs(pts) - half).min(axis=1)
    truth = np.all(np.abs(pts) < half, axis=1)
    clear = gap > 1e-9  # points on the surface may go either way
    np.testing.assert_array_equal(InsideTest(box).contains(pts)[clear], truth[clear])
    shape = concave_test_shapes()["l_shape"]  # 8 × 6 cm, arms 2 cm thick, 3 cm deep, centred
    offset = np.array([0.04, 0.03, 0.015])
    x, y, z = (_queries(shape.bounds) + offset).T
    inside_xy = ((x > 0) & (x < 0.08) & (y > 0) & (y < 0.02)) | ((x > 0) & (x < 0.02) & (y > 0) & (y < 0.06))
    truth = inside_xy & (z > 0) & (z < 0.03)
    on = np.zeros_like(x, dtype=bool)
    for coord, planes in ((x, (0, 0.02, 0.08)), (y, (0, 0.02, 0.06)), (z, (0, 0.03))):
        for c in planes:
            on |= np.abs(coord - c) < 1e-9
    got = InsideTest(shape).contains(np.c_[x, y, z] - offset)
    np.testing.assert_array_equal(got[~on], truth[~on])


def test_torus_hole_is_outside() -> None:
    torus = concave_test_shapes()["torus"]  # major 3 cm, minor 1 cm (tessellated: test away from the surface)
    pts = _queries(torus.bounds)
    ring = np.hypot(np.hypot(pts[:, 0], pts[:, 1]) - 0.03, pts[:, 2])
    clear = np.abs(ring - 0.01) > 5e-4
    np.testing.assert_array_equal(InsideTest(torus).contains(pts)[clear], (ring < 0.01)[clear])
    assert not InsideTest(torus).contains(np.zeros((1, 3)))[0]
