"""Exact closest points on meshes: an analytic box, and every face of a real fingertip mesh."""

import numpy as np
import trimesh

from manifoundation.core.geometry.closest import TriangleSet, mesh_triangles


def _box_distance(x: np.ndarray, half: np.ndarray) -> np.ndarray:
    """Analytic unsigned distance from points (M, 3) to the surface of an origin-centred box."""
    q = np.abs(x) - half
    outside = np.linalg.norm(np.maximum(q, 0.0), axis=1)
    inside = -np.max(q, axis=1)  # depth below the nearest face, for points inside
    return np.where(np.all(q <= 0, axis=1), inside, outside)


def test_box_distances_match_the_analytic_ones_inside_and_out():
    half = np.array([0.02, 0.03, 0.05])
    mesh = trimesh.creation.box(extents=2 * half)
    x = np.random.default_rng(0).uniform(-0.08, 0.08, size=(300, 3))
    points, dist = TriangleSet.of(mesh).closest(x)
    np.testing.assert_allclose(dist, _box_distance(x, half), atol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(points - x, axis=1), dist, atol=1e-12)
    assert np.all(np.abs(points) <= half + 1e-12)  # on the box


def test_a_fingertip_mesh_agrees_with_every_face_and_unused_vertices_are_ignored():
    from manifoundation.core.robots import get_hand

    hand = get_hand("leap")
    mesh = hand.collision_meshes[hand.fingertip_bodies[0]]
    rng = np.random.default_rng(1)
    x = mesh.vertices[rng.integers(0, len(mesh.vertices), 40)] + rng.normal(scale=0.004, size=(40, 3))
    _, dist = TriangleSet.of(mesh).closest(x)
    every = np.array([
        np.linalg.norm(trimesh.triangles.closest_point(mesh.triangles, np.repeat(p[None], len(mesh.faces), 0)) - p,
                       axis=1).min()
        for p in x
    ])  # fmt: skip
    np.testing.assert_allclose(dist, every, atol=1e-12)
    # a vertex no face uses must not bound the search (it would leave no candidate face)
    stray = trimesh.Trimesh(np.vstack([mesh.vertices, x[:1]]), mesh.faces, process=False)
    np.testing.assert_allclose(TriangleSet.of(stray).closest(x[:1])[1], every[:1], atol=1e-12)


def test_the_object_set_is_built_once_per_mesh():
    mesh = trimesh.creation.box(extents=[0.04, 0.04, 0.04])
    assert mesh_triangles(mesh) is mesh_triangles(mesh)


def test_signed_distances_match_the_analytic_box_inside_and_out():
    from manifoundation.core.geometry.closest import mesh_signed_distance

    half = np.array([0.02, 0.03, 0.05])
    mesh = trimesh.creation.box(extents=2 * half)
    x = np.random.default_rng(2).uniform(-0.07, 0.07, size=(400, 3))
    x = np.concatenate([x, mesh.vertices + 1e-4, mesh.vertices - 1e-4])  # beside the corners: vertex features
    np.testing.assert_allclose(mesh_signed_distance(mesh, x), -_box_distance(x, half) * np.where(
        np.all(np.abs(x) <= half, axis=1), -1.0, 1.0), atol=1e-12)  # fmt: skip


def test_signed_distances_on_curved_and_long_faced_meshes_agree_with_every_face_and_the_ray_test():
    """An icosphere (edges and vertices between curved faces) and a capsule stretched into a pen (long faces that
    every point must box-test): magnitudes against every face, sides against trimesh's ray-parity test."""
    from manifoundation.core.geometry.closest import mesh_signed_distance

    pen = trimesh.creation.capsule(height=0.14, radius=0.005, count=[48, 48])
    assert len(TriangleSet.of(pen).large) > 0
    for mesh in (trimesh.creation.icosphere(3, 0.04), pen):
        rng = np.random.default_rng(3)
        x = mesh.vertices[rng.integers(0, len(mesh.vertices), 60)] + rng.normal(scale=0.003, size=(60, 3))
        sd = mesh_signed_distance(mesh, x)
        every = np.array([
            np.linalg.norm(trimesh.triangles.closest_point(mesh.triangles, np.repeat(p[None], len(mesh.faces), 0)) - p,
                           axis=1).min()
            for p in x
        ])  # fmt: skip
        np.testing.assert_allclose(np.abs(sd), every, atol=1e-12)
        inside = mesh.contains(x)
        clear = every > 1e-6
        assert np.array_equal((sd > 0)[clear], inside[clear])
        assert inside.any() and (~inside).any()
