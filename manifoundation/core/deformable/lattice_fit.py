"""A plasticine cloud that is a lattice body's boundary, rebuilt as exactly that body.

The plasticine generator (`manifoundation.core.deformable.plasticine`) cuts a body from an axis-aligned cubic lattice
and shows its boundary vertices as the cloud. When a caller's cloud is such a boundary — every point on one axis-aligned
lattice of spacing h, to 1 % of a cell — the body is determined: the cubes whose centre the oriented cloud encloses
(generalised winding number ≥ ½; a cube centre lies half a cell from the nearest boundary face, where the points'
winding number is unambiguous), split by `manifoundation.core.deformable.lattice.cube_tetrahedra` with the parity
counted from the body's own lowest cube, as the generator counts it. The fit is accepted only when the rebuilt body's
boundary vertices are exactly the caller's points (same set, one each); otherwise the cloud is not a lattice
boundary and `manifoundation.core.deformable.reconstruct` fills it with a lattice of its own instead.

Why: a body filled on a lattice of its own differs from the caller's by up to half a cell at the surface, and
the same press then ends 0.01-0.09 away in the metric's 2 m cube — ten times the 3D success threshold (0.005) —
so a rollout could not judge a plasticine answer on the caller's object.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from scipy.spatial import cKDTree

from manifoundation.core.deformable.lattice import boundary, cube_tetrahedra

ON_LATTICE = 0.01  # largest offset from a lattice node, in cells, for a point to count as on it (a cloud sent
# rounded to 10 µm is still the lattice: the nodes are the vertices, the points are embedded where they are)


class LatticeBody(NamedTuple):
    """vertices (V, 3) m, tetrahedra (T, 4), the boundary vertices (N,) with their outward normals (N, 3), and each
    caller's point's vertex (N,)."""

    vertices: np.ndarray
    tetrahedra: np.ndarray
    surface: np.ndarray
    surface_normals: np.ndarray
    point_vertex: np.ndarray


def lattice_body(points: np.ndarray, normals: np.ndarray) -> LatticeBody | None:
    """The lattice body whose boundary vertices are ``points``, or None when there is none.

    Args:
        points: (N, 3) the cloud, m. normals: (N, 3) its outward unit normals.

    Returns:
        The body; None when the points are not one axis-aligned lattice's nodes or the cubes their winding number
        encloses have another boundary.
    """
    from manifoundation.core.refine.field import PointCloudField

    p = np.asarray(points, dtype=np.float64)
    if len(p) < 8:
        return None
    gaps, _ = cKDTree(p).query(p, k=2)
    h = float(np.median(gaps[:, 1]))
    if not h > 0:
        return None
    origin = p.min(axis=0)
    for _ in range(2):  # the nodes, then the spacing and origin that fit them best (least squares)
        nodes = np.rint((p - origin) / h).astype(np.int64)
        h, origin = _fitted_lattice(p, nodes)
        if not h > 0:
            return None
    cell = (p - origin) / h
    nodes = np.rint(cell).astype(np.int64)
    if np.abs(cell - nodes).max() > ON_LATTICE or len(np.unique(nodes, axis=0)) != len(p):
        return None
    dims = nodes.max(axis=0)
    if np.any(dims < 1):
        return None
    grid = np.stack(np.meshgrid(*(np.arange(d) for d in dims), indexing="ij"), axis=-1).reshape(-1, 3)
    field = PointCloudField(p, np.asarray(normals, dtype=np.float64))
    cubes = grid[field.winding_number(origin + (grid + 0.5) * h) >= 0.5]
    if len(cubes) == 0:
        return None
    ijk, tets = cube_tetrahedra(cubes)
    vertices = origin + ijk * h
    surface, surface_normals = boundary(vertices, tets)
    index = {tuple(v): i for i, v in enumerate(ijk.tolist())}
    owner = np.array([index.get(tuple(v), -1) for v in nodes.tolist()])
    if np.any(owner < 0) or len(surface) != len(p) or not np.array_equal(np.sort(owner), surface):
        return None
    return LatticeBody(vertices, tets, surface, surface_normals, owner)


def _fitted_lattice(points: np.ndarray, nodes: np.ndarray) -> tuple[float, np.ndarray]:
    """The spacing h and origin (3,) minimising Σ ‖points − origin − h·nodes‖² (nodes (N, 3) integers)."""
    n = len(points)
    design = np.zeros((3 * n, 4))
    design[:, 0] = nodes.T.reshape(-1)
    for axis in range(3):
        design[axis * n:(axis + 1) * n, 1 + axis] = 1.0
    solution = np.linalg.lstsq(design, points.T.reshape(-1), rcond=None)[0]
    return float(solution[0]), solution[1:]
