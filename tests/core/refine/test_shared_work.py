"""The work the hot paths share instead of repeating gives the same numbers as the plain computation."""

import numpy as np
import scipy.sparse as sp
import torch

from manifoundation.core.refine.conic import ConicProblem, Rows
from manifoundation.core.refine.contact import surface_contacts
from manifoundation.core.refine.field import PointCloudField
from manifoundation.core.refine.state import HandPose, sphere_kinematics


def test_the_problems_matrix_is_scipys_of_the_dense_stack():
    """Blocks given dense and as `Rows` (identities, blocks side by side) stack, kind by kind, into the matrix
    scipy makes of the same rows written out densely."""
    rng = np.random.default_rng(0)
    n = 25
    dense = rng.normal(size=(6, n)) * (rng.random((6, n)) < 0.3)
    dense[2], dense[:, 4] = 0.0, 0.0  # an empty row and column
    side = rng.normal(size=(4, 10))
    side[1, 3] = 0.0  # an explicit zero in a sparse block is left out
    prob = ConicProblem(n)
    prob.leq(Rows.beside(Rows.dense(side, 2), Rows.eye(4, 20, -1.0)), np.zeros(4))
    prob.soc(Rows.dense(np.eye(3), 12), np.zeros(3))
    prob.zero(dense, np.ones(6))
    prob.leq(Rows.eye(n, 0), np.ones(n))
    written = np.zeros((4, n))
    written[:, 2:12], written[:, 20:24] = side, -np.eye(4)
    cone = np.zeros((3, n))
    cone[:, 12:15] = np.eye(3)
    expected = sp.csc_matrix(np.vstack([dense, written, np.eye(n), cone]))  # zero, nonneg (in order), soc
    a, b, cones = prob.constraints()
    assert a.shape == expected.shape and len(b) == expected.shape[0] and len(cones) == 3
    np.testing.assert_array_equal(a.indptr, expected.indptr)
    np.testing.assert_array_equal(a.indices, expected.indices)
    np.testing.assert_array_equal(a.data, expected.data)


def _near_pose(hand, cloud, seed):
    """The rest hand moved so that its first fingertip's pad sits on the object's surface (guards active)."""
    rng = np.random.default_rng(seed)
    q = np.clip(np.asarray(hand.rest) + rng.normal(scale=0.2, size=hand.dof), hand.lower, hand.upper)
    pose = HandPose(np.zeros(3), np.array([1.0, 0, 0, 0]), q)
    with torch.no_grad():
        tip = hand.fingertips(*pose.tensors())[0, 0].numpy()
    target = cloud.points[rng.integers(len(cloud.points))]
    return HandPose(target - tip, pose.palm_quat, q)


def test_spheres_from_the_contact_models_body_poses_are_the_hands(box, gripper):
    from manifoundation.core.robots import get_hand

    _, pts, nrm = box
    cloud = PointCloudField(pts, nrm)
    for hand in (gripper, get_hand("leap")):
        pose = _near_pose(hand, cloud, 1)
        found = surface_contacts(hand, pose.tensors(), cloud)
        with torch.no_grad():
            want_p, want_j = hand.spheres(*pose.tensors())
            got_p, got_j = sphere_kinematics(hand, pose.tensors(), found.body_poses)
        torch.testing.assert_close(got_p, want_p, rtol=0, atol=1e-15)
        torch.testing.assert_close(got_j, want_j, rtol=0, atol=1e-15)


def test_contacts_without_guards_are_the_same_contacts(box):
    """Verification measures only the pads: the contact samples, their projection and gaps do not change, and the
    projection equals the field's own (the object-point query the linearisation no longer repeats)."""
    from manifoundation.core.robots import get_hand

    _, pts, nrm = box
    cloud = PointCloudField(pts, nrm)
    hand = get_hand("leap")
    for seed in range(3):
        pose = _near_pose(hand, cloud, seed)
        full = surface_contacts(hand, pose.tensors(), cloud)
        pads = surface_contacts(hand, pose.tensors(), cloud, jacobian=False, guards=False)
        assert len(full.clear) > 0 and len(pads.clear) == 0
        np.testing.assert_array_equal(pads.sample, full.sample)
        np.testing.assert_array_equal(pads.nearest, full.nearest)
        np.testing.assert_allclose(pads.phi, full.phi, rtol=0, atol=1e-15)
        phi, grad, _ = cloud.signed_distance(full.points)
        np.testing.assert_allclose(full.object_points(cloud), full.points - phi[:, None] * grad, rtol=0, atol=1e-15)


def test_cells_hold_every_sample_once_in_cell_runs(box):
    """The winding number's near field walks each near cell's run of samples (``start``, ``count``): the runs
    tile the sorted samples and hold every sample exactly once."""
    _, pts, nrm = box
    cloud = PointCloudField(pts, nrm)
    cells = cloud._cells()
    np.testing.assert_array_equal(cells.start[1:], cells.start[:-1] + cells.count[:-1])
    assert cells.start[0] == 0 and cells.count.sum() == len(pts)
    assert sorted(map(tuple, np.round(cells.points, 12))) == sorted(map(tuple, np.round(pts, 12)))


def test_part_grid_bounds_hold_and_the_pruned_guards_are_the_same_rows(box):
    """A convex part's clearance lies between its grid's bounds everywhere the guards look, and the object-point
    guards measured on the pruned points are the rows measured on every point (LEAP: hulls of up to 4 800 faces)."""
    from manifoundation.core.refine.object_guards import OBJECT_GUARD_MARGIN, object_guards, part_grids_of
    from manifoundation.core.refine.part_bounds import clearance
    from manifoundation.core.robots import get_hand

    hand = get_hand("leap")
    rng = np.random.default_rng(0)
    parts, grids = hand.fingertip_parts[3], part_grids_of(hand)[3]
    for (planes, bounds), grid in zip(parts, grids, strict=True):
        x = rng.uniform(bounds[0] - OBJECT_GUARD_MARGIN, bounds[1] + OBJECT_GUARD_MARGIN, size=(500, 3))
        lower, upper = grid.bounds(x)
        exact = clearance(planes, x)[0]
        assert np.all(lower <= exact + 1e-12) and np.all(exact <= upper + 1e-12)
    _, pts, nrm = box
    cloud = PointCloudField(pts, nrm)
    compared = 0
    for seed in range(6):
        pose = _near_pose(hand, cloud, seed)
        with torch.no_grad():
            T_all = hand.tree.body_poses(*pose.tensors())[0].numpy()
        for i, body in enumerate(hand.fingertip_body_index):
            centre = T_all[body, :3, :3] @ hand.contact_surface.bound_centre[i] + T_all[body, :3, 3]
            radius = float(hand.contact_surface.bound_radius[i])
            want = object_guards(cloud, hand.fingertip_parts[i], T_all[body], centre, radius)
            got = object_guards(cloud, hand.fingertip_parts[i], T_all[body], centre, radius, part_grids_of(hand)[i])
            for a, b in zip(want, got, strict=True):
                np.testing.assert_allclose(b, a, rtol=0, atol=1e-15)
            compared += len(want[0])
    assert compared > 0


def test_bounded_contacts_are_the_contacts_of_every_sample(box):
    """Measuring only the samples their representatives' distances cannot rule out gives the same contacts, gaps
    and guard rows as measuring every pad and near-body sample (the cover's bound holds on the points' field)."""
    from manifoundation.core.refine.cover import sample_cover
    from manifoundation.core.robots import get_hand

    _, pts, nrm = box
    cloud = PointCloudField(pts, nrm)
    hand = get_hand("leap")
    cover = sample_cover(hand)
    assert np.all(cover.delta[cover.rep == np.arange(len(cover.rep))] == 0.0)
    assert len(np.unique(cover.rep)) < len(cover.rep) / 3
    for seed in range(4):
        pose = _near_pose(hand, cloud, seed)
        full = surface_contacts(hand, pose.tensors(), cloud, bounded=False)
        part = surface_contacts(hand, pose.tensors(), cloud)
        assert len(full.clear) > 0
        for name in ("sample", "nearest", "phi", "gap", "point_gap", "clear", "clear_grad", "row_jac", "projected"):
            np.testing.assert_array_equal(getattr(part, name), getattr(full, name), err_msg=name)
