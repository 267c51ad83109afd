import numpy as np
import pytest
import trimesh

from manifoundation.core.refine.field import PointCloudField


@pytest.fixture(scope="module")
def sphere_field():
    mesh = trimesh.creation.icosphere(subdivisions=4, radius=0.05)
    pts, faces = trimesh.sample.sample_surface(mesh, 4000, seed=1)
    return PointCloudField(np.asarray(pts), np.asarray(mesh.face_normals[faces]))


def test_signed_distance_close_to_exact(sphere_field):
    rng = np.random.default_rng(0)
    d = rng.normal(size=(200, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    r = rng.uniform(0.03, 0.09, size=200)
    phi, grad, _ = sphere_field.signed_distance(d * r[:, None])
    np.testing.assert_allclose(phi, r - 0.05, atol=1.5e-3)
    outside = r > 0.06
    assert np.all(np.einsum("ij,ij->i", grad[outside], d[outside]) > 0.8)


def test_box_edge_has_no_sign_jumps(box):
    _, pts, nrm = box
    field = PointCloudField(pts, nrm)
    # walk around an edge 1 cm outside the box: Φ stays positive and continuous
    angles = np.linspace(0, np.pi / 2, 200)
    path = np.stack([0.02 + 0.01 * np.cos(angles), np.zeros_like(angles), 0.03 + 0.01 * np.sin(angles)], axis=1)
    phi = field.signed_distance(path)[0]
    assert np.all(phi > 0.005)
    assert np.max(np.abs(np.diff(phi))) < 2e-3


def test_region_distance_and_normals(sphere_field):
    mask = sphere_field.points[:, 2] > 0.04
    masked = PointCloudField(sphere_field.points, sphere_field.normals, mask)
    dist, grad = masked.region_distance(np.array([[0, 0, 0.06], [0.06, 0, 0]]))
    assert dist[0] < 0.015 and dist[1] > 0.03
    np.testing.assert_allclose(np.linalg.norm(grad, axis=1), 1.0)
    n = sphere_field.surface_normal(np.array([[0, 0, 0.05]]))
    assert n[0, 2] > 0.99
    jac = sphere_field.normal_jacobian(np.array([[0, 0, 0.05]]))
    assert 0.3 / 0.05 < jac[0, 0, 0] < 3 / 0.05  # of the order of the curvature 1/R
    with pytest.raises(ValueError):
        PointCloudField(sphere_field.points, sphere_field.normals, np.zeros(len(sphere_field.points), bool))


def test_region_distance_vanishes_on_the_region_and_is_continuous_across_samples(sphere_field):
    mask = sphere_field.points[:, 2] > 0.03
    masked = PointCloudField(sphere_field.points, sphere_field.normals, mask)
    theta = np.linspace(0.0, 1.3, 600)  # a meridian on the surface, leaving the region at z = 0.03 (θ ≈ 0.93)
    path = 0.05 * np.stack([np.sin(theta), np.zeros_like(theta), np.cos(theta)], axis=1)
    value, grad = masked.region_distance(path)
    inside = theta < 0.85
    point = masked.region_point_distance(path[inside])
    assert value[inside].max() < 2e-3 and value[inside].mean() < 0.5 * point.mean()  # near 0 between samples
    assert np.all(value[inside] <= point + 1e-12)
    assert np.max(np.abs(np.diff(value))) < 1e-3  # no jumps where the nearest sample changes
    assert value[-1] > 0.01 and np.all(np.diff(value[theta > 1.0]) > 0)
    np.testing.assert_allclose(np.linalg.norm(grad, axis=1), 1.0)
    assert grad[-1] @ np.array([-np.cos(1.3), 0.0, np.sin(1.3)]) < -0.9  # outside: it points away from the region


def _concave_shapes():
    import trimesh

    cup = trimesh.creation.annulus(r_min=0.03, r_max=0.036, height=0.08)
    torus = trimesh.creation.torus(0.04, 0.012)
    return [("cup", cup), ("torus", torus), ("L", _l_prism())]


def _l_prism():
    """A watertight L-shaped part (8 × 7 cm, 2 cm arms, 3 cm thick), triangulated by hand."""
    import trimesh

    outline = np.array([[0, 0], [0.08, 0], [0.08, 0.02], [0.02, 0.02], [0.02, 0.07], [0, 0.07]])
    verts = np.vstack([np.c_[outline, np.zeros(6)], np.c_[outline, np.full(6, 0.03)]])
    cap = [[0, 1, 2], [0, 2, 3], [0, 3, 4], [0, 4, 5]]
    faces = [f[::-1] for f in cap] + [[a + 6, b + 6, c + 6] for a, b, c in cap]
    for i in range(6):
        j = (i + 1) % 6
        faces += [[i, j, j + 6], [i, j + 6, i + 6]]
    mesh = trimesh.Trimesh(verts, np.asarray(faces))
    trimesh.repair.fix_normals(mesh)
    assert mesh.is_watertight and mesh.volume > 0
    return mesh


@pytest.mark.parametrize("index", [0, 1, 2])
def test_points_surface_keeps_concavities(index):
    """Inside a cup's opening, a torus' hole and an L's inner corner, points that are outside the exact mesh read
    outside (a convex hull calls them 15-20 mm deep), and the depth error stays within the sample spacing."""
    import trimesh

    name, mesh = _concave_shapes()[index]
    pts, faces = trimesh.sample.sample_surface(mesh, 4096, seed=0)
    field = PointCloudField(pts, mesh.face_normals[faces])
    rng = np.random.default_rng(0)
    probe, _ = trimesh.sample.sample_surface(mesh, 2000, seed=1)
    probe = probe + rng.normal(size=probe.shape) * 0.004
    exact = -trimesh.proximity.signed_distance(mesh, probe)  # trimesh: positive inside
    hull = -trimesh.proximity.signed_distance(mesh.convex_hull, probe)
    phi = field.signed_distance(probe)[0]
    concave = (exact > 0.003) & (hull < -0.003)  # outside the object, inside its hull
    assert concave.sum() > 20, name
    assert np.all(phi[concave] > 0), name
    clear = np.abs(exact) > 0.0015
    assert np.mean(np.sign(phi[clear]) == np.sign(exact[clear])) > 0.995, name
    assert np.percentile(np.abs(phi - exact), 99) < 2.5e-3, name


def test_the_hull_test_with_probe_facets_agrees_with_every_facet():
    from scipy.spatial import ConvexHull

    from manifoundation.core.refine.field import HULL_MARGIN

    rng = np.random.default_rng(3)
    pts = rng.normal(size=(2048, 3)) * [0.05, 0.03, 0.02]
    pts /= np.linalg.norm(pts / [0.05, 0.03, 0.02], axis=1, keepdims=True)  # an ellipsoid's surface
    field = PointCloudField(pts, pts / np.linalg.norm(pts, axis=1, keepdims=True))
    x = rng.uniform(-0.07, 0.07, size=(5000, 3))
    hull = ConvexHull(pts).equations
    grow = HULL_MARGIN * field.disc_radius
    in_box = np.all((x >= pts.min(0) - grow) & (x <= pts.max(0) + grow), axis=1)
    expected = in_box & (np.max(x @ hull[:, :3].T + hull[:, 3], axis=1) <= grow)
    got = field.within_hull(x)
    np.testing.assert_array_equal(got, expected)
    assert 0 < got.sum() < len(x)  # both answers occur
