"""A plasticine cloud that is a lattice body's boundary is rebuilt as exactly that body; other clouds are not."""

from __future__ import annotations

import numpy as np
import pytest

from manifoundation.core.deformable.lattice_fit import lattice_body
from manifoundation.core.deformable.plasticine import PLASTICINE_KINDS, make_plasticine


@pytest.mark.parametrize("kind", PLASTICINE_KINDS)
def test_the_generators_bodies_are_recovered_vertex_for_vertex(kind: str) -> None:
    for seed in (0, 1):
        body = make_plasticine(kind, seed)
        fit = lattice_body(body.points, body.normals)
        assert fit is not None
        np.testing.assert_allclose(fit.vertices, body.vertices, atol=1e-12)
        np.testing.assert_array_equal(fit.tetrahedra, body.elements)
        np.testing.assert_array_equal(fit.point_vertex, body.surface)  # each point is its own vertex


def test_a_cloud_off_the_lattice_or_rotated_is_not_a_lattice_body() -> None:
    body = make_plasticine("box", 1)
    rng = np.random.default_rng(0)
    jittered = body.points + rng.normal(scale=1e-3, size=body.points.shape)
    assert lattice_body(jittered, body.normals) is None
    c, s = np.cos(0.3), np.sin(0.3)
    turn = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    assert lattice_body(body.points @ turn.T, body.normals @ turn.T) is None


def test_a_cloud_sent_rounded_to_10_um_is_still_its_lattice_body() -> None:
    body = make_plasticine("ellipsoid", 2)
    fit = lattice_body(body.points.round(5), body.normals.round(4))
    assert fit is not None
    np.testing.assert_allclose(fit.vertices, body.vertices, atol=2e-5)
    np.testing.assert_array_equal(fit.tetrahedra, body.elements)


def test_missing_boundary_points_leave_no_exact_body() -> None:
    body = make_plasticine("sphere", 0)
    assert lattice_body(body.points[5:], body.normals[5:]) is None
