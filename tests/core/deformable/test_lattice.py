"""The lattice tetrahedra: a conforming mesh that fills the cubes and does not lean along one diagonal."""

from __future__ import annotations

import numpy as np

from manifoundation.core.deformable.body import DeformableBody
from manifoundation.core.deformable.lattice import boundary
from manifoundation.core.deformable.plasticine import make_plasticine, tetrahedralise
from manifoundation.core.deformable.simulate import simulate


def _box(p: np.ndarray) -> np.ndarray:
    return np.all(np.abs(p) <= 0.5 + 1e-9, axis=1)


def test_the_mirrored_split_fills_the_cubes_and_conforms() -> None:
    vertices, tets = tetrahedralise(_box, 4)
    a, b, c, d = (vertices[tets[:, i]] for i in range(4))
    volumes = np.abs(np.einsum("ij,ij->i", b - a, np.cross(c - a, d - a))) / 6.0
    assert np.all(volumes > 1e-9)
    assert np.isclose(volumes.sum(), 1.0)
    faces = np.sort(np.concatenate([tets[:, [1, 2, 3]], tets[:, [0, 2, 3]], tets[:, [0, 1, 3]], tets[:, [0, 1, 2]]]),
                    axis=1)  # fmt: skip
    _, counts = np.unique(faces, axis=0, return_counts=True)
    assert counts.max() == 2  # a face is shared by two tetrahedra at most: no overlap, no hanging face
    surface, _ = boundary(vertices, tets)
    on_hull = np.any(np.isclose(np.abs(vertices), 0.5), axis=1)
    assert set(surface.tolist()) == set(np.flatnonzero(on_hull).tolist())  # no crack inside: boundary = the box's


def test_a_straight_press_on_a_mirrored_box_moves_it_as_its_mirror_image() -> None:
    """Kuhn's split everywhere slid this body 1.4 mm along x under a central press; mirrored, x drifts ≤ 0.1 mm."""
    body = make_plasticine("box", 1)
    mirrored_vertices = body.vertices * np.array([-1.0, 1.0, 1.0])
    mirrored = DeformableBody(body.material, body.kind, mirrored_vertices, body.elements, body.surface,
                              body.normals * np.array([-1.0, 1.0, 1.0]), body.properties, body.seed)  # fmt: skip
    points = body.points
    top = points[:, 2] > points[:, 2].max() - 1e-6
    gap = np.where(top, np.linalg.norm(points[:, :2] - points[:, :2].mean(axis=0), axis=1), np.inf)
    pressed = np.argsort(gap)[:4]
    press = np.tile([0.0, 0.0, -0.015], (4, 1))
    drift = [(simulate(b, pressed, press).vertices - b.vertices).mean(axis=0) for b in (body, mirrored)]
    assert abs(drift[0][0]) < 1e-4 and abs(drift[1][0]) < 1e-4
    assert np.allclose(drift[0] * np.array([-1.0, 1.0, 1.0]), drift[1], atol=1e-4)
    dent = simulate(body, pressed, press).vertices[body.surface[pressed], 2] - body.points[pressed, 2]
    assert np.all(dent < -0.008)  # the pressed points keep most of the 1.5 cm


def test_the_split_depends_on_the_cubes_not_on_where_their_lattice_began() -> None:
    from manifoundation.core.deformable.lattice import cube_tetrahedra

    cubes = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [1, 1, 1]])
    ijk, tets = cube_tetrahedra(cubes)
    shift = np.array([3, 1, 2])  # odd and even shifts
    shifted_ijk, shifted_tets = cube_tetrahedra(cubes + shift)
    np.testing.assert_array_equal(shifted_ijk, ijk + shift)
    np.testing.assert_array_equal(shifted_tets, tets)
    assert np.all(np.diff(ijk @ [100, 10, 1]) > 0)  # vertices in lexicographic order
