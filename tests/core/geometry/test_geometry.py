"""Analytic checks: box/sphere SDF, normal estimation, mass properties, Kabsch, penetration depths."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh
from scipy.spatial.transform import Rotation

from manifoundation.core.geometry import (
    DEFAULT_DENSITY,
    InvalidPointCloud,
    ObjectGeometry,
    fit_rigid_motion,
    hand_object_penetration,
    hand_self_collision,
    rotation_vector,
)
from manifoundation.core.robots import get_hand, load_hand


def _sphere_cloud(r: float = 0.05, n: int = 4000, centre=(0.0, 0.0, 0.0)) -> ObjectGeometry:  # type: ignore[no-untyped-def]
    g = np.random.default_rng(0)
    d = g.normal(size=(n, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    mesh = trimesh.creation.icosphere(subdivisions=4, radius=r)
    mesh.apply_translation(centre)
    return ObjectGeometry.from_points(np.asarray(centre) + r * d, d, mesh)


def _box_cloud(ext=(0.1, 0.06, 0.04), n: int = 6000) -> ObjectGeometry:  # type: ignore[no-untyped-def]
    mesh = trimesh.creation.box(extents=ext)
    pts, face = trimesh.sample.sample_surface_even(mesh, n, seed=0)
    return ObjectGeometry.from_points(pts, mesh.face_normals[face], mesh)


def test_sphere_signed_distance_and_gradient() -> None:
    geom = _sphere_cloud()
    x = np.array([[0.08, 0, 0], [0, 0.0, -0.03], [0.0, 0.0, 0.05]])
    phi, grad, idx = geom.signed_distance(x)
    np.testing.assert_allclose(phi, [0.03, -0.02, 0.0], atol=2e-3)
    np.testing.assert_allclose(grad, x / np.linalg.norm(x, axis=1, keepdims=True), atol=0.05)
    assert idx.shape == (3,)


def test_box_signed_distance() -> None:
    geom = _box_cloud()
    phi, grad, _ = geom.signed_distance(np.array([[0.07, 0, 0], [0, 0, -0.01], [0.0, 0.05, 0.0]]))
    np.testing.assert_allclose(phi, [0.02, -0.01, 0.02], atol=1e-9)
    np.testing.assert_allclose(grad, [[1, 0, 0], [0, 0, -1], [0, 1, 0]], atol=1e-9)


def test_estimated_normals_point_outward() -> None:
    ref = _sphere_cloud()
    geom = ObjectGeometry.from_points(ref.points)
    cos = np.einsum("ij,ij->i", geom.normals, ref.normals)
    assert np.mean(cos > 0.9) > 0.99
    assert abs(geom.volume - 4 / 3 * np.pi * 0.05**3) / (4 / 3 * np.pi * 0.05**3) < 0.02  # convex hull


def test_masked_distance_uses_allowed_region_only() -> None:
    geom = _box_cloud()
    mask = geom.points[:, 0] > 0.049  # the +x face only
    x = np.array([[0.0, 0.0, 0.05]])  # 3 cm above the +z face
    phi, grad, idx = geom.masked_signed_distance(x, mask)
    assert mask[idx[0]]
    assert phi[0] > 0.049  # it must travel to the +x face
    np.testing.assert_allclose(np.linalg.norm(grad, axis=1), 1.0)
    top = geom.points[:, 2] > 0.019  # another mask: the +z face, right below the query (cached tree replaced)
    phi2, grad2, _ = geom.masked_signed_distance(x, top)
    assert phi2[0] == pytest.approx(0.03, abs=2e-3)
    np.testing.assert_allclose(grad2[0], [0, 0, 1], atol=0.1)
    with pytest.raises(InvalidPointCloud):
        geom.masked_signed_distance(x, np.zeros(len(geom.points), bool))


def test_box_mass_properties() -> None:
    a, b, c = 0.1, 0.06, 0.04
    geom = _box_cloud((a, b, c))
    mp = geom.mass_properties(density=800.0)
    m = 800.0 * a * b * c
    assert mp.mass == pytest.approx(m, rel=1e-9)
    np.testing.assert_allclose(mp.com, 0.0, atol=1e-12)
    expected = m / 12 * np.diag([b * b + c * c, a * a + c * c, a * a + b * b])
    np.testing.assert_allclose(mp.inertia, expected, atol=1e-12)
    assert geom.mass_properties().mass == pytest.approx(DEFAULT_DENSITY * a * b * c)


def test_kabsch_recovers_exact_transform() -> None:
    g = np.random.default_rng(1)
    p = g.normal(size=(50, 3))
    R = Rotation.from_rotvec([0.3, -0.5, 1.1]).as_matrix()
    t = np.array([0.1, -0.2, 0.05])
    fit = fit_rigid_motion(p, p @ R.T + t)
    np.testing.assert_allclose(fit.rotation, R, atol=1e-12)
    np.testing.assert_allclose(fit.translation, t, atol=1e-12)
    np.testing.assert_allclose(rotation_vector(fit.rotation), [0.3, -0.5, 1.1], atol=1e-12)
    assert fit.rms < 1e-12
    noisy = fit_rigid_motion(p, p @ R.T + t + g.normal(scale=1e-3, size=p.shape))
    assert 5e-4 < noisy.rms < 2e-3
    w = np.ones(50)
    w[0] = 0.0
    target = p @ R.T + t
    target[0] += 10.0  # an outlier with zero weight is ignored
    np.testing.assert_allclose(fit_rigid_motion(p, target, w).rotation, R, atol=1e-12)


def test_kabsch_never_returns_a_reflection() -> None:
    p = np.random.default_rng(2).normal(size=(20, 3))
    fit = fit_rigid_motion(p, p * np.array([1, 1, -1]))
    assert np.linalg.det(fit.rotation) == pytest.approx(1.0)


BOX_HAND = b"""<robot name="box"><link name="palm"><collision><geometry><box size="0.2 0.2 0.1"/></geometry>
</collision></link><link name="f"><collision><origin xyz="0 0 0.2"/><geometry><box size="0.01 0.01 0.01"/>
</geometry></collision></link><joint name="j" type="prismatic"><parent link="palm"/><child link="f"/>
<axis xyz="1 0 0"/><limit lower="0" upper="0.01"/></joint></robot>"""


@pytest.mark.parametrize("d", [0.0, 0.004, 0.012])
def test_penetration_depth_of_sphere_into_box(d: float) -> None:
    hand = load_hand(BOX_HAND, fingertips=["f"])  # a 20 x 20 x 10 cm box palm, top face at z = 0.05
    r = 0.03
    geom = _sphere_cloud(r=r, centre=(0.01, -0.02, 0.05 + r - d))
    depth = hand_object_penetration(hand, geom, np.zeros(3), np.array([1.0, 0, 0, 0]), np.zeros(1))
    assert depth == pytest.approx(d, abs=5e-4)
    far = _sphere_cloud(r=r, centre=(0.0, 0.0, 0.3))
    assert hand_object_penetration(hand, far, np.zeros(3), np.array([1.0, 0, 0, 0]), np.zeros(1)) == 0.0


def test_self_collision_of_a_builtin() -> None:
    hand = get_hand("panda_gripper")
    quat = np.array([1.0, 0, 0, 0])
    assert hand_self_collision(hand, np.zeros(3), quat, hand.rest) == 0.0
    hand2 = get_hand("barrett")
    q = hand2.rest.copy()
    assert hand_self_collision(hand2, np.zeros(3), quat, q) == 0.0
    q[hand2.joint_names.index("bh_j12")] = 2.4  # fingers 1 and 2 close fully onto finger 3
    q[hand2.joint_names.index("bh_j22")] = 2.4
    q[hand2.joint_names.index("bh_j32")] = 2.4
    assert hand_self_collision(hand2, np.zeros(3), quat, q) > 0.005


def test_open_mesh_falls_back_to_a_watertight_hull() -> None:
    box = trimesh.creation.box(extents=(0.1, 0.1, 0.1))
    open_box = trimesh.Trimesh(box.vertices, box.faces[:-2])  # one face missing
    pts, face = trimesh.sample.sample_surface_even(box, 500, seed=0)
    geom = ObjectGeometry.from_points(pts, box.face_normals[face], open_box)
    assert geom.mesh.is_watertight and geom.volume == pytest.approx(1e-3, rel=1e-6)


@pytest.mark.parametrize(
    "points, normals",
    [(np.zeros((3, 3)), None), (np.full((10, 3), np.nan), None), (np.zeros((10, 2)), None),
     (np.random.default_rng(0).normal(size=(10, 3)), np.zeros((10, 3)))],
)  # fmt: skip
def test_invalid_clouds_are_rejected(points: np.ndarray, normals: np.ndarray | None) -> None:
    with pytest.raises(InvalidPointCloud):
        ObjectGeometry.from_points(points, normals)


def test_builtin_hand_penetration_and_rigid_motion_invariance() -> None:
    """A ball between the fingers penetrates; moving hand and ball together changes nothing."""
    import torch

    hand = get_hand("allegro")
    d = torch.float64
    tips = hand.fingertips(torch.zeros(1, 3, dtype=d), torch.tensor([[1.0, 0, 0, 0]], dtype=d),
                           torch.as_tensor(hand.rest[None]))[0].numpy()  # fmt: skip
    centre = tips.mean(0)
    geom = _sphere_cloud(r=0.04, n=2000, centre=tuple(centre))
    quat = np.array([1.0, 0, 0, 0])
    depth = hand_object_penetration(hand, geom, np.zeros(3), quat, hand.rest)
    assert depth > 0.005
    R = Rotation.from_rotvec([0.2, -0.4, 0.3])
    t = np.array([0.3, -0.1, 0.2])
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = R.as_matrix(), t
    moved = ObjectGeometry.from_points(
        R.apply(geom.points) + t, R.apply(geom.normals), geom.mesh.copy().apply_transform(T)
    )
    xyzw = R.as_quat()
    depth2 = hand_object_penetration(hand, moved, t, np.array([xyzw[3], *xyzw[:3]]), hand.rest)
    assert depth2 == pytest.approx(depth, abs=1e-6)
    far = _sphere_cloud(r=0.04, n=2000, centre=(0.5, 0.5, 0.5))
    assert hand_object_penetration(hand, far, np.zeros(3), quat, hand.rest) == 0.0


def test_link_poses_at_one_pose_are_computed_once_and_match_the_kinematics():
    import torch

    from manifoundation.core.geometry.link_poses import link_poses_at
    from manifoundation.core.robots import get_hand

    hand = get_hand("allegro")
    pos, quat = np.array([0.01, -0.02, 0.3]), np.array([0.9, 0.1, -0.3, 0.2]) / np.linalg.norm([0.9, 0.1, -0.3, 0.2])
    q = np.asarray(hand.rest, dtype=np.float64) + 0.1
    first = link_poses_at(hand, pos, quat, q)
    assert link_poses_at(hand, pos.copy(), quat.copy(), q.copy()) is first  # the same pose: no second FK
    with torch.no_grad():
        exact = hand.link_poses(*(torch.as_tensor(a[None]) for a in (pos, quat, q)))
    for name, pose in first.items():
        np.testing.assert_array_equal(pose, exact[name][0].numpy())
    other = link_poses_at(hand, pos + np.array([0.0, 0.0, 0.01]), quat, q)
    assert other is not first
    np.testing.assert_allclose(other[hand.fingertip_bodies[0]][:3, 3] - first[hand.fingertip_bodies[0]][:3, 3],
                               [0.0, 0.0, 0.01], atol=1e-12)


def test_depth_inside_a_convex_part_by_chunks_of_half_spaces_is_the_depth_against_all_at_once() -> None:
    """An icosphere's 320 facets as half-spaces: points dropped chunk by chunk leave the deepest point's depth
    (its distance to the nearest facet plane) as measuring every point against every plane does."""
    from manifoundation.core.geometry.collision import _inside_depth

    hull = trimesh.creation.icosphere(2, 0.01)
    planes = np.column_stack([hull.face_normals, np.einsum("fa,fa->f", hull.face_normals, hull.triangles_center)])
    rng = np.random.default_rng(5)
    for grow in (0.0, 0.002):
        for x in (rng.uniform(-0.015, 0.015, size=(3000, 3)), rng.uniform(0.011, 0.02, size=(50, 3))):
            every = (planes[:, 3][None] + grow - x @ planes[:, :3].T).min(axis=1)
            assert _inside_depth(planes, x, None, grow) == pytest.approx(max(float(every.max()), 0.0), abs=1e-15)



def test_field_penetration_measured_through_the_cover_is_every_samples() -> None:
    """`hand_field_penetration` measures a body's samples only where their cube's representative allows them
    inside (Φ bounded by the distance to it and the discs' radius): LEAP's bodies against a box's points, from deep
    in it to grazing it to clear of it, give the depth every sample gives, and most samples are skipped."""
    import torch

    from manifoundation.core.geometry.collision import _bodies, hand_field_penetration, samples_depth
    from manifoundation.core.geometry.link_poses import link_poses_at
    from manifoundation.core.refine.field import PointCloudField

    hand = get_hand("leap")
    d = torch.float64
    tips = hand.fingertips(torch.zeros(1, 3, dtype=d), torch.tensor([[1.0, 0, 0, 0]], dtype=d),
                           torch.as_tensor(hand.rest[None]))[0].numpy()  # fmt: skip
    box = trimesh.creation.box(extents=[0.03, 0.04, 0.05])
    pts, face = trimesh.sample.sample_surface_even(box, 2048, seed=0)
    quat = np.array([1.0, 0, 0, 0])
    poses = link_poses_at(hand, np.zeros(3), quat, hand.rest)
    shallow, deep, clear = 0, 0, 0
    for shift in (0.0, *np.arange(0.015, 0.035, 0.002), 0.2):
        field = PointCloudField(np.asarray(pts) + tips.mean(0) + [shift, 0, 0], box.face_normals[face])
        inflate = field.resolution
        for body in _bodies(hand):
            T = poses[body.name]
            world = body.samples @ T[:3, :3].T + T[:3, 3]
            phi = field.signed_distance(world)[0]
            behind = np.flatnonzero(phi < inflate)
            every = float(max(inflate - field.robust_signed_distance(world[behind]).min(), 0.0)) if len(behind) else 0.0
            assert samples_depth(field, world, body.cover, inflate) == every, (shift, body.name)
            assert len(body.cover.representatives) < len(world) / 2
            shallow += 0 < every < 2e-3
            deep += every > 5e-3
        clear += hand_field_penetration(hand, field, np.zeros(3), quat, hand.rest, inflate=inflate) == 0.0
    assert shallow and deep and clear  # the poses span all three


def test_a_grid_cover_puts_every_sample_within_a_cube_diagonal_of_its_own_cubes_representative() -> None:
    from manifoundation.core.geometry.sample_cover import SampleCover

    x = np.random.default_rng(2).uniform(-0.05, 0.05, size=(5000, 3))
    cell = 0.01
    cover = SampleCover.grid(x, cell)
    reps = np.unique(cover.rep)
    assert np.array_equal(cover.rep[reps], reps)  # a representative is its own
    assert cover.delta.max() <= np.sqrt(3) * cell and np.allclose(cover.delta, np.linalg.norm(x - x[cover.rep], axis=1))
    cube = np.floor((x - x.min(0)) / cell).astype(int)
    assert np.array_equal(cube, cube[cover.rep])  # a sample's representative lies in its cube
    assert len(reps) == len(np.unique(cube, axis=0)) < len(x)
