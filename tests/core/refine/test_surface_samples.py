"""Distances on the exact surface's samples when the caller's cloud is sparse (checked on an analytic sphere)."""

from __future__ import annotations

import numpy as np
import trimesh

from manifoundation.core.refine.field import PointCloudField
from manifoundation.core.refine.surface_samples import DENSE_ENOUGH, mesh_surface_samples

RADIUS = 0.15


def _sphere_cloud(count: int, seed: int = 0) -> tuple[trimesh.Trimesh, np.ndarray, np.ndarray]:
    mesh = trimesh.creation.icosphere(subdivisions=5, radius=RADIUS)
    points, faces = trimesh.sample.sample_surface(mesh, count, seed=seed)
    return mesh, np.asarray(points), np.asarray(mesh.face_normals[faces])


def _probes(count: int = 2000) -> tuple[np.ndarray, np.ndarray]:
    """Points 0-4 mm outside the analytic sphere and their true distances to it (|x| − R)."""
    rng = np.random.default_rng(1)
    u = rng.normal(size=(count, 3))
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    gap = rng.uniform(0.0, 4e-3, size=count)
    return u * (RADIUS + gap)[:, None], gap


def test_a_sparse_cloud_gets_samples_and_its_distances_follow_the_true_surface() -> None:
    mesh, points, normals = _sphere_cloud(2048)
    sparse = PointCloudField(points, normals)
    samples = mesh_surface_samples(mesh, sparse.disc_radius)
    assert samples is not None and len(samples.points) > 10 * len(points)
    dense = PointCloudField(points, normals, surface=samples)
    x, gap = _probes()
    error_sparse = sparse.signed_distance(x)[0] - gap
    error_dense = dense.signed_distance(x)[0] - gap
    # the sparse field reads the surface several mm farther than it is between its points (the tessellation
    # lies within 0.1 mm of the analytic sphere at 5 subdivisions)
    assert np.quantile(error_sparse, 0.99) > 3e-3
    assert np.quantile(np.abs(error_dense), 0.99) < 1.5e-3
    assert dense.resolution < 1.2e-3 < 4e-3 < sparse.resolution


def test_the_caller_points_keep_the_normals_the_region_and_the_side() -> None:
    mesh, points, normals = _sphere_cloud(512)
    mask = points[:, 2] > 0
    plain = PointCloudField(points, normals, mask)
    samples = mesh_surface_samples(mesh, plain.disc_radius)
    assert samples is not None
    dense = PointCloudField(points, normals, mask, samples)
    x = np.array([[0.0, 0.0, RADIUS + 0.01], [0.0, 0.0, RADIUS - 0.01], [0.0, 0.0, 0.0]])
    np.testing.assert_array_equal(dense.nearest_index(x), plain.nearest_index(x))
    np.testing.assert_array_equal(dense.given_normal(x), plain.given_normal(x))
    np.testing.assert_array_equal(dense.region_point_distance(x), plain.region_point_distance(x))
    phi = dense.signed_distance(x)[0]
    assert phi[0] > 0 > phi[1] and phi[2] < -0.1
    assert dense.winding_number(x[2:])[0] > 0.9


def test_no_samples_for_a_dense_cloud_or_an_open_mesh() -> None:
    mesh = _sphere_cloud(2048)[0]
    assert mesh_surface_samples(mesh, DENSE_ENOUGH) is None
    open_mesh = mesh.copy()
    open_mesh.update_faces(np.arange(len(mesh.faces)) > 10)
    assert not open_mesh.is_watertight
    assert mesh_surface_samples(open_mesh, 5e-3) is None


def test_the_standoff_left_without_samples_fits_within_the_verifications_contact_tolerance() -> None:
    """A cloud gets no samples up to DENSE_ENOUGH: its standoff (its disc radius) plus where the refinement stops
    must stay within the tip tolerance the verification measures on the mesh, or its grasps cannot pass."""
    from manifoundation.core.refine.refine import RefineConfig
    from manifoundation.core.refine.verify import TIP_TOL

    assert DENSE_ENOUGH + RefineConfig().tip_tol <= TIP_TOL
