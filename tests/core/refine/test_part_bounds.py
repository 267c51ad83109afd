"""`PartGrid.bounds`' compiled loop against its numpy formula, and the bounds against the exact clearance."""

from __future__ import annotations

import numpy as np

from manifoundation.core.refine.part_bounds import PartGrid, clearance


def test_grid_bounds_match_the_numpy_formula_and_bound_the_clearance():
    rng = np.random.default_rng(11)
    normals = rng.normal(size=(60, 3))
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    planes = np.concatenate([normals, np.full((60, 1), 0.01)], axis=1)  # a polytope round a 1 cm ball
    grid = PartGrid.build(planes, np.array([[-0.012] * 3, [0.012] * 3]), margin=0.005)
    x = rng.uniform(-0.016, 0.016, size=(400, 3))
    lower, upper = grid.bounds(x)

    corners = np.array([[i, j, k] for i in (0, 1) for j in (0, 1) for k in (0, 1)])
    rel = (x - grid.origin) / grid.step
    cell = np.clip(np.floor(rel).astype(np.int64), 0, np.asarray(grid.values.shape) - 2)
    frac = rel - cell
    at = cell[:, None, :] + corners[None]
    v = grid.values[at[..., 0], at[..., 1], at[..., 2]]
    weight = np.prod(np.where(corners[None] == 1, frac[:, None, :], 1.0 - frac[:, None, :]), axis=2)
    np.testing.assert_allclose(upper, np.sum(weight * v, axis=1), rtol=0, atol=1e-15)
    gap = np.linalg.norm((frac[:, None, :] - corners[None]) * grid.step, axis=2)
    np.testing.assert_allclose(lower, np.max(v - gap, axis=1), rtol=0, atol=1e-15)

    exact = clearance(planes, x)[0]
    assert np.all(lower <= exact + 1e-12) and np.all(exact <= upper + 1e-12)
    assert np.mean(upper - lower) < 3 * grid.step  # bounds that prune


def test_clearance_is_the_largest_face_excess():
    rng = np.random.default_rng(12)
    planes = np.concatenate([rng.normal(size=(300, 3)), rng.uniform(0.0, 0.01, size=(300, 1))], axis=1)
    x = rng.normal(scale=0.01, size=(50, 3))
    value, face = clearance(planes, x)
    excess = x @ planes[:, :3].T - planes[:, 3]
    np.testing.assert_allclose(value, excess.max(axis=1), rtol=0, atol=1e-15)
    np.testing.assert_array_equal(face, excess.argmax(axis=1))
    assert clearance(planes, np.zeros((0, 3)))[0].shape == (0,)
