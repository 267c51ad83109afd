"""Every compiled loop of the science (numba), compiled or loaded from numba's cache ahead of the first request.

`make install` calls `warm_up` once, so the loops are compiled on the machine before anything runs (≈ 3-4 s) and
two workers starting together only load them; a worker calls it as it starts (≈ 0.3 s from the cache), so no
request pays for it.
"""

from __future__ import annotations

import time

import numpy as np


def warm_up() -> float:
    """Call each compiled loop once on a tiny input; returns the seconds it took."""
    from manifoundation.core.refine.field_kernels import disc_distances, winding_sum, within_facets
    from manifoundation.core.refine.part_bounds import _clearance, _grid_bounds
    from manifoundation.core.refine.self_pairs import near_pairs
    from manifoundation.core.robots.kinematics_kernels import (
        apply_delta_one,
        body_poses_one,
        on_bodies_one,
        point_jacobian_one,
    )

    t0 = time.perf_counter()
    point, one = np.zeros((1, 3)), np.ones(1)
    first, ones = np.zeros(1, dtype=np.int64), np.ones(1, dtype=np.int64)
    disc_distances(point, first.reshape(1, 1), point, np.ones((1, 3)), 0.1)
    winding_sum(point, point, one, point, first, ones, point, point, 2.0, 0.1)
    within_facets(point, -np.ones(3), np.ones(3), np.zeros((1, 4)), np.zeros((1, 4)), 0.1)
    _clearance(np.zeros((1, 4)), point)
    _grid_bounds(point, np.zeros(3), 0.1, np.zeros((2, 2, 2)))
    near_pairs(np.zeros((2, 3)), np.ones(2), np.array([[0, 1]]))
    poses = body_poses_one(np.zeros(3), np.array([1.0, 0, 0, 0]), np.zeros(1), first, one, np.zeros(1), one,
                           np.zeros(1), np.ones((1, 3)), np.eye(4)[None], np.array([-1]))  # fmt: skip
    point_jacobian_one(poses, first, point, np.zeros(3), np.ones((1, 3)), one, np.zeros(1), np.ones((1, 1, 1)))
    apply_delta_one(np.zeros(3), np.array([1.0, 0, 0, 0]), np.zeros(1), np.zeros(7))
    on_bodies_one(poses, first, point, True)
    return time.perf_counter() - t0


if __name__ == "__main__":
    print(f"compiled loops ready in {warm_up():.2f} s")
