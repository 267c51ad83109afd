"""The point field's compiled loops against the plain numpy formulas they replace, written out here."""

from __future__ import annotations

import numpy as np
import pytest

from manifoundation.core.refine.field_kernels import disc_distances, winding_sum, within_facets


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


@pytest.fixture
def samples() -> tuple[np.ndarray, np.ndarray]:
    """300 points on a 5 cm sphere with their outward normals, tilted by noise (so discs disagree)."""
    rng = np.random.default_rng(3)
    points = 0.05 * _unit(rng.normal(size=(300, 3)))
    normals = _unit(points + 0.01 * rng.normal(size=(300, 3)))
    return points, normals


def test_disc_distances_match_the_numpy_formula(samples):
    points, normals = samples
    rng = np.random.default_rng(4)
    x = 0.05 * _unit(rng.normal(size=(64, 3))) * rng.uniform(0.8, 1.3, size=(64, 1))
    x[0] = points[7]  # on a sample: inside its disc, a = 0
    h, k = 0.004, 8
    idx = np.argsort(np.linalg.norm(x[:, None] - points[None], axis=2), axis=1)[:, :k]
    nearest, best, side, weight, grad = disc_distances(x, idx, points, normals, h)

    p, n = points[idx], normals[idx]
    d = x[:, None] - p
    a = np.sum(d * n, axis=2)
    tang = d - a[..., None] * n
    b = np.linalg.norm(tang, axis=2)
    e = np.maximum(b - h, 0.0)
    value = np.hypot(a, e)
    j = np.argmin(value, axis=1)
    rows = np.arange(len(x))
    np.testing.assert_allclose(nearest, value[rows, j], rtol=0, atol=1e-15)
    np.testing.assert_array_equal(best, idx[rows, j])
    w = np.exp(-(((value - value[rows, j][:, None]) / h) ** 2))
    cos = a / np.maximum(value, 1e-12)
    np.testing.assert_allclose(side, np.sum(w * cos * np.abs(cos), axis=1), rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(weight, w.sum(axis=1), rtol=1e-12)
    a_b, e_b, n_b, t_b, b_b = a[rows, j], e[rows, j], n[rows, j], tang[rows, j], b[rows, j]
    outside_rim = (a_b[:, None] * n_b + e_b[:, None] * t_b / np.maximum(b_b, 1e-12)[:, None]) / np.maximum(
        value[rows, j], 1e-12)[:, None]  # fmt: skip
    expected = np.where((e_b <= 0)[:, None], np.sign(a_b + 1e-300)[:, None] * n_b, outside_rim)
    np.testing.assert_allclose(grad, expected, rtol=0, atol=1e-12)
    assert (e_b <= 0).any() and (e_b > 0).any()  # both branches were exercised
    np.testing.assert_allclose(np.linalg.norm(grad, axis=1), 1.0, atol=1e-9)  # a distance's gradient is unit


def test_winding_sum_with_every_cell_near_is_the_plain_sum(samples):
    points, normals = samples
    rng = np.random.default_rng(5)
    area = rng.uniform(0.5, 1.5, size=len(points)) * 4 * np.pi * 0.05**2 / len(points)
    weighted = normals * area[:, None]
    cell = (np.arange(len(points)) % 7).astype(np.int64)  # 7 cells of interleaved samples, sorted by cell
    order = np.argsort(cell, kind="stable")
    count = np.bincount(cell)
    start = np.cumsum(count) - count
    centre = np.stack([points[cell == c].mean(0) for c in range(7)])
    moment = np.stack([weighted[cell == c].sum(0) for c in range(7)])
    radius = np.full(7, 1e-9)  # tiny cells: with far = inf every cell is summed sample by sample
    x = np.array([[0.0, 0.0, 0.0], [0.01, -0.02, 0.005], [0.2, 0.0, 0.0], [0.0, 0.0, 0.049]])
    floor = 1e-3
    got = winding_sum(x, centre, radius, moment, start, count, points[order], weighted[order], np.inf, floor)
    d = points[None] - x[:, None]
    r = np.maximum(np.linalg.norm(d, axis=2), floor)
    np.testing.assert_allclose(got, np.sum(np.sum(d * weighted[None], axis=2) / r**3, axis=1), rtol=1e-12)
    # every cell far (radius 1e-9, far = 1): each contributes its dipole at its centre
    dipole = winding_sum(x[2:3], centre, radius, moment, start, count, points[order], weighted[order], 1.0, floor)
    dc = centre - x[2]
    np.testing.assert_allclose(dipole, [np.sum(np.sum(dc * moment, axis=1) / np.linalg.norm(dc, axis=1) ** 3)])
    assert got[0] / (4 * np.pi) == pytest.approx(1.0, abs=0.05)  # the centre of a closed surface: inside
    assert abs(got[2] / (4 * np.pi)) < 0.05  # far outside


def test_within_facets_is_every_plane_and_the_box():
    rng = np.random.default_rng(6)
    normals = _unit(rng.normal(size=(40, 3)))
    equations = np.concatenate([normals, np.full((40, 1), -0.05)], axis=1)  # n·x ≤ 0.05: a polytope round a ball
    probe = equations[:5].copy()
    lo, hi = np.full(3, -0.06), np.full(3, 0.06)
    x = rng.uniform(-0.08, 0.08, size=(500, 3))
    grow = 0.004
    got = within_facets(x, lo, hi, probe, equations, grow)
    planes = np.max(x @ equations[:, :3].T + equations[:, 3], axis=1) <= grow
    box = np.all((x >= lo) & (x <= hi), axis=1)
    np.testing.assert_array_equal(got, planes & box)
    assert got.any() and (~got).any()
