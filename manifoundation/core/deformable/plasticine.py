"""Plasticine blobs: spheres, boxes, ellipsoids, composites (unions of ellipsoids) and bumpy blobs, as tetrahedra.

A shape is an implicit inside test on a cubic lattice of spacing h (about ``cells`` cells across the longest
side); every lattice cube whose eight corners are inside is split into six tetrahedra (Kuhn's split, mirrored
in every other cube so that the lattice does not lean along one diagonal: `manifoundation.core.deformable.lattice`). The
cloud is the boundary vertices (those on faces used by one tetrahedron only); their normals are the
area-weighted outward normals of those faces. Sizes (longest side) are drawn in ``PLASTICINE_SIZE``; the body
rests on the table.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from manifoundation.core.deformable.body import DeformableBody
from manifoundation.core.deformable.lattice import CORNERS, boundary, cube_tetrahedra
from manifoundation.core.deformable.materials import sample_properties

PLASTICINE_SIZE = (0.04, 0.1)  # m
Inside = Callable[[np.ndarray], np.ndarray]


def _ellipsoid(axes: np.ndarray, centre: np.ndarray | None = None) -> Inside:
    c = np.zeros(3) if centre is None else centre
    return lambda p: (np.square((p - c) / axes).sum(axis=1) <= 1.0)


def _shape(kind: str, rng: np.random.Generator) -> Inside:
    if kind == "sphere":
        return _ellipsoid(np.full(3, 0.5))
    if kind == "box":
        half = rng.uniform(0.25, 0.5, size=3)
        half[int(np.argmax(half))] = 0.5
        return lambda p: np.all(np.abs(p) <= half + 1e-9, axis=1)
    if kind == "ellipsoid":
        axes = rng.uniform(0.25, 0.5, size=3)
        axes[int(np.argmax(axes))] = 0.5
        return _ellipsoid(axes)
    if kind == "composite":
        parts = [_ellipsoid(rng.uniform(0.18, 0.35, size=3), rng.uniform(-0.08, 0.08, size=3))
                 for _ in range(int(rng.integers(2, 4)))]  # fmt: skip
        return lambda p: np.any([part(p) for part in parts], axis=0)
    if kind == "blob":
        bumps = [(d / np.linalg.norm(d), rng.uniform(-0.12, 0.12)) for d in rng.normal(size=(4, 3))]

        def inside(p: np.ndarray) -> np.ndarray:
            r = np.linalg.norm(p, axis=1)
            u = p / np.maximum(r, 1e-12)[:, None]
            radius = 0.4 + sum(a * np.exp(-(1 - u @ d) / 0.3) for d, a in bumps)
            return np.asarray(r <= radius)

        return inside
    raise ValueError(f"kind: {kind!r} is not a plasticine shape ({', '.join(PLASTICINE_KINDS)})")


PLASTICINE_KINDS = ("sphere", "box", "ellipsoid", "composite", "blob")


def tetrahedralise(inside: Inside, cells: int, keep: str = "corners") -> tuple[np.ndarray, np.ndarray]:
    """Lattice tetrahedra of an implicit shape in [−0.5, 0.5]³: vertices (V, 3), tetrahedra (T, 4).

    ``keep`` "corners" keeps the cubes whose eight corners are inside (the body lies within the shape);
    "centres" those whose centre is (the body's boundary lies within half a cell of the shape's, either side,
    and its volume is about the shape's).
    """
    h = 1.0 / cells
    ticks = np.arange(-0.5, 0.5 + h / 2, h)
    n = len(ticks)
    if keep == "centres":
        mid = ticks[:-1] + h / 2
        grid = np.stack(np.meshgrid(mid, mid, mid, indexing="ij"), axis=-1).reshape(-1, 3)
        cubes = np.argwhere(inside(grid).reshape(n - 1, n - 1, n - 1))
    else:
        ijk = np.stack(np.meshgrid(np.arange(n), np.arange(n), np.arange(n), indexing="ij"), axis=-1).reshape(-1, 3)
        flag = inside(ticks[ijk]).reshape(n, n, n)
        cubes = np.argwhere(np.all([flag[c[0]:n - 1 + c[0], c[1]:n - 1 + c[1], c[2]:n - 1 + c[2]]
                                    for c in CORNERS], axis=0))  # fmt: skip
    if len(cubes) == 0:
        raise ValueError("shape holds no lattice cube; use more cells")
    vertex_ijk, tets = cube_tetrahedra(cubes)
    return ticks[vertex_ijk], tets


def make_plasticine(kind: str, seed: int, properties: dict[str, float] | None = None, size: float | None = None,
                    cells: int = 6, min_points: int = 80) -> DeformableBody:  # fmt: skip
    """A plasticine body of shape ``kind`` (one of `PLASTICINE_KINDS`) resting on the table.

    Args:
        kind: shape name.
        seed: draws the shape, the size and (when ``properties`` is None) the properties.
        properties: plasticine properties (default: sampled).
        size: longest side in metres (default: drawn in `PLASTICINE_SIZE`).
        cells: lattice cells across the unit cube the shape is drawn in (the first try).
        min_points: refine the lattice (one cell more at a time, up to 16) until the cloud has this many points.
    """
    rng = np.random.default_rng(seed)
    inside = _shape(kind, rng)
    scale = float(rng.uniform(*PLASTICINE_SIZE)) if size is None else float(size)
    props = sample_properties("plasticine", rng) if properties is None else dict(properties)
    for n in range(cells, 17):
        try:
            unit, tets = tetrahedralise(inside, n)
        except ValueError:
            continue
        verts = (unit - unit.mean(axis=0)) * scale / np.ptp(unit, axis=0).max()
        verts[:, 2] -= verts[:, 2].min() - 1e-3
        surface, normals = boundary(verts, tets)
        if len(surface) >= min_points:
            break
    else:
        raise ValueError(f"kind {kind!r}, seed {seed}: fewer than {min_points} surface points at 16 cells")
    return DeformableBody("plasticine", kind, verts, tets, surface, normals, props, seed)
