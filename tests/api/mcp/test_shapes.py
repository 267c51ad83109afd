"""The primitive objects agents name by size: closed meshes of the right volume, points on them, normals out
(checked with trimesh, independently of how they are built)."""

from __future__ import annotations

import math

import numpy as np
import pytest
import trimesh

from manifoundation.server.api.mcp.shapes import primitive


@pytest.mark.parametrize(
    ("shape", "size", "volume"),
    [
        ("box", [0.04, 0.06, 0.08], 0.04 * 0.06 * 0.08),
        ("sphere", [0.03], 4 / 3 * math.pi * 0.03**3),
        ("cylinder", [0.03, 0.1], math.pi * 0.03**2 * 0.1),
    ],
)
def test_primitive_is_a_closed_surface_with_outward_normals(shape: str, size: list[float], volume: float) -> None:
    obj = primitive(shape, size, 512, friction=0.6)  # type: ignore[arg-type]
    assert obj.mesh is not None and obj.num_points == 512 and obj.properties.friction == 0.6
    mesh = trimesh.Trimesh(obj.mesh.vertices, obj.mesh.faces, process=False)
    assert mesh.is_watertight and mesh.is_winding_consistent
    assert mesh.volume == pytest.approx(volume, rel=0.03)  # a 32-segment polygon is 0.6 % short of the circle
    assert np.abs(trimesh.proximity.signed_distance(mesh, obj.points)).max() < 1e-3  # on the surface
    outside = trimesh.proximity.signed_distance(mesh, obj.points + 2e-3 * obj.normals)
    assert (outside < 0).all()  # trimesh: negative outside
    np.testing.assert_allclose(np.linalg.norm(obj.normals, axis=1), 1.0, atol=1e-9)


def test_same_shape_same_points_and_bad_sizes_name_the_field() -> None:
    np.testing.assert_array_equal(primitive("box", [0.1, 0.1, 0.1]).points, primitive("box", [0.1, 0.1, 0.1]).points)
    for shape, size in (("box", [0.1, 0.1]), ("sphere", [-0.1]), ("cylinder", [0.1, float("nan")])):
        with pytest.raises(ValueError, match=r"^size: "):
            primitive(shape, size)  # type: ignore[arg-type]
