"""Labels: kernel, masks, the inverse of Eq. 4, per-point motions."""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from manifoundation.core.objects import make_object
from manifoundation.core.refine.grasp import cone_rows, grasp_maps
from manifoundation.core.refine.wrench import kabsch, motion_from_pose, normalise, wrench_from_motion
from research.data.examples import ObjectInfo, is_unseen_motion, make_example, sample_forces
from research.data.labels import (
    HEAT_SIGMA,
    contact_wrench,
    heat_and_force,
    joint_point_motion,
    motion_from_wrench,
    region_mask,
    rigid_point_motion,
    scale_motion,
)


def _cloud(n: int = 400, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    p = rng.normal(size=(n, 3))
    p /= np.linalg.norm(p, axis=1, keepdims=True)
    return p * 0.1, p.copy()


def test_heatmap_peaks_at_contacts_and_force_map_reads_the_force() -> None:
    pts, nrm = _cloud()
    contacts, cn = pts[[3, 200]], nrm[[3, 200]]
    forces = np.array([[0.1, 0.2, -0.3], [0.0, -0.5, 0.1]])
    heat, fmap = heat_and_force(pts, nrm, contacts, cn, forces, scale=0.2)
    assert heat.shape == (400,) and fmap.shape == (400, 3)
    assert np.all((heat >= 0) & (heat <= 1))
    np.testing.assert_allclose(heat[[3, 200]], 1.0)
    np.testing.assert_allclose(fmap[3], forces[0], atol=1e-3)
    # half height at about 1.18 sigma s; far points ~0
    d = np.minimum(np.linalg.norm(pts - contacts[0], axis=1), np.linalg.norm(pts - contacts[1], axis=1))
    assert np.all(heat[d > 5 * HEAT_SIGMA * 0.2] < 1e-4)


def test_region_mask_all_ones_or_neighbourhood() -> None:
    pts, _ = _cloud()
    contacts = pts[[5, 50]]
    kinds = set()
    for s in range(20):
        m = region_mask(pts, contacts, 0.2, np.random.default_rng(s))
        assert m.dtype == bool and m[[5, 50]].all()
        kinds.add(bool(m.all()))
    assert kinds == {True, False}


def test_motion_from_wrench_inverts_eq4_and_survives_the_pipeline_round_trip() -> None:
    obj = make_object("box", 0.2, 1, num_points=512)
    info = ObjectInfo.from_object(obj)
    w = np.array([0.3, -0.2, 0.5, 0.01, 0.02, -0.015])
    dx, dth = motion_from_wrench(w, info.mass, info.inertia)
    np.testing.assert_allclose(wrench_from_motion(dx, dth, info.mass, info.inertia), w, rtol=1e-9, atol=1e-12)
    dx, dth = scale_motion(info.points, info.centre, dx, dth, 0.02)
    motion = rigid_point_motion(info.points, info.centre, dx, dth)
    rot, t = kabsch(info.points, info.points + motion)
    dx2, dth2 = motion_from_pose(rot, t, info.centre)
    w2 = wrench_from_motion(dx2, dth2, info.mass, info.inertia)
    np.testing.assert_allclose(normalise(w2), normalise(w), atol=1e-6)


def test_joint_motion_rotates_about_the_axis() -> None:
    pts, _ = _cloud(50)
    origin, axis = np.array([0.1, 0, 0]), np.array([0, 0, 1.0])
    m = joint_point_motion(pts, "revolute", axis, origin, 0.3)
    rot = Rotation.from_rotvec(axis * 0.3).as_matrix()
    np.testing.assert_allclose(pts + m, (pts - origin) @ rot.T + origin, atol=1e-12)
    np.testing.assert_allclose(joint_point_motion(pts, "prismatic", axis, origin, 0.05), np.tile([0, 0, 0.05], (50, 1)))


def test_forces_in_cones_and_examples_are_consistent() -> None:
    obj = make_object("cylinder", 0.15, 3, num_points=512)
    info = ObjectInfo.from_object(obj)
    rng = np.random.default_rng(0)
    idx = [0, 100, 300]
    contacts, normals = obj.points[idx], obj.normals[idx]
    f = sample_forces(normals, 0.5, rng)
    c = np.einsum("mij,mj->mi", cone_rows(normals, 0.5), f)
    assert np.all(c[:, 0] >= np.linalg.norm(c[:, 1:], axis=1) - 1e-12)
    for articulated in (False, True):
        for unseen in (False, True):
            e = make_example(info, contacts, normals, rng, want_unseen=unseen, articulated=articulated)
            if e is None:
                continue
            w = np.einsum("mij,mj->i", grasp_maps(contacts, info.centre, info.length), e["forces"])
            assert is_unseen_motion(w) == unseen
            assert np.max(np.einsum("ij,ij->i", e["forces"], -normals)) <= 1.0 + 1e-9
            if not articulated:
                np.testing.assert_allclose(np.linalg.norm(w), 1.0, rtol=1e-9)
                # the motion's wrench direction is the contacts' wrench direction
                w_unscaled = contact_wrench(contacts, e["forces"], info.centre)
                w_motion = wrench_from_motion(e["delta_x"], e["delta_theta"], info.mass, info.inertia)
                np.testing.assert_allclose(normalise(w_motion), normalise(w_unscaled), atol=1e-9)
            assert e["motion"].shape == (512, 3) and e["heat"].max() > 0.9
