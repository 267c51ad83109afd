"""Lattice tetrahedra shared by the solid bodies (plasticine blobs, rope rods): Kuhn's cube split and boundaries.

Kuhn's split cuts a cube into six tetrahedra around its main diagonal (corner 0 to corner 7); neighbouring cubes
split this way share their face diagonals, so the tetrahedra conform. Split the same way everywhere, a lattice
leans along that diagonal: a straight press on a symmetric block slides it 1.4-4.5 mm sideways (measured,
docs/deformables.md). `mirrored_kuhn` reflects the split in every odd cube along each axis, so each cube is the
mirror image of its neighbours across their shared face (which keeps the face diagonals shared) and the lattice
has the cube grid's mirror symmetries. `cube_tetrahedra` counts the parity from the body's own lowest cube, so the
same cubes give the same tetrahedra wherever the lattice they were cut from began (a body rebuilt from its cloud,
`manifoundation.core.deformable.lattice_fit`, is then the generator's mesh). The boundary of a tetrahedral mesh is the
faces used by one tetrahedron only; a boundary vertex's normal is the area-weighted sum of its faces' outward
normals.
"""

from __future__ import annotations

import numpy as np

# Kuhn's six tetrahedra of the unit cube, corners indexed by (x, y, z) bits: 0 = (0,0,0) ... 7 = (1,1,1).
KUHN = np.array([[0, 1, 3, 7], [0, 3, 2, 7], [0, 2, 6, 7], [0, 6, 4, 7], [0, 4, 5, 7], [0, 5, 1, 7]])
CORNERS = np.array([[(c >> 0) & 1, (c >> 1) & 1, (c >> 2) & 1] for c in range(8)])


def mirrored_kuhn(cubes: np.ndarray, corner_ids: np.ndarray) -> np.ndarray:
    """Tetrahedra (6C, 4) of lattice cubes, Kuhn's split mirrored along each axis where the cube's index is odd.

    Args:
        cubes: (C, 3) integer lattice index of each cube's corner 0.
        corner_ids: (C, 8) vertex id of each cube's corners, in `CORNERS` order.
    """
    mask = (cubes[:, 0] % 2) | ((cubes[:, 1] % 2) << 1) | ((cubes[:, 2] % 2) << 2)
    local = KUHN[None] ^ mask[:, None, None]  # reflecting axis a maps corner c to c XOR (1 << a)
    tets: np.ndarray = np.take_along_axis(np.repeat(corner_ids[:, None, :], 6, axis=1), local, axis=2)
    return tets.reshape(-1, 4)


def cube_tetrahedra(cubes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The mirrored Kuhn tetrahedra of a set of lattice cubes, parity counted from their lowest index per axis.

    Args:
        cubes: (C, 3) integer lattice index of each cube's corner 0.

    Returns:
        The used lattice vertices (V, 3) as integer indices, in lexicographic order, and the tetrahedra (6C, 4)
        over them.
    """
    cubes = np.asarray(cubes, dtype=np.int64).reshape(-1, 3)
    base = cubes.min(axis=0)
    rel = cubes - base
    dims = tuple(int(d) for d in rel.max(axis=0) + 2)
    corners = (rel[:, None, :] + CORNERS[None]).reshape(-1, 3)
    ids = np.ravel_multi_index(tuple(corners.T), dims).reshape(-1, 8)
    used, tets = np.unique(mirrored_kuhn(rel, ids), return_inverse=True)
    ijk = np.stack(np.unravel_index(used, dims), axis=1) + base
    return ijk, tets.reshape(-1, 4)


def boundary(vertices: np.ndarray, tets: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Boundary vertex indices (N,) and their outward unit normals (N, 3)."""
    faces = np.concatenate([tets[:, [1, 2, 3]], tets[:, [0, 2, 3]], tets[:, [0, 1, 3]], tets[:, [0, 1, 2]]])
    opposite = np.concatenate([tets[:, 0], tets[:, 1], tets[:, 2], tets[:, 3]])
    key = np.sort(faces, axis=1)
    _, first, counts = np.unique(key, axis=0, return_index=True, return_counts=True)
    outer = first[counts == 1]
    f, o = faces[outer], opposite[outer]
    n = np.cross(vertices[f[:, 1]] - vertices[f[:, 0]], vertices[f[:, 2]] - vertices[f[:, 0]])
    n *= np.where(np.einsum("ij,ij->i", n, vertices[f[:, 0]] - vertices[o]) < 0, -1.0, 1.0)[:, None]
    acc = np.zeros_like(vertices)
    for k in range(3):
        np.add.at(acc, f[:, k], n)
    surface = np.unique(f)
    normals = acc[surface] / np.linalg.norm(acc[surface], axis=1, keepdims=True)
    return surface, normals
