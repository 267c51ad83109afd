"""The work the hot paths share instead of repeating gives the same numbers as the plain computation."""

import numpy as np
import scipy.sparse as sp
import torch

from models.refine.conic import dense_to_csc
from models.refine.contact import surface_contacts
from models.refine.field import PointCloudField
from models.refine.state import HandPose, sphere_kinematics


def test_dense_to_csc_is_scipys_matrix():
    rng = np.random.default_rng(0)
    a = rng.normal(size=(60, 25)) * (rng.random((60, 25)) < 0.2)
    a[3], a[:, 4] = 0.0, 0.0  # an empty row and column
    x, y = sp.csc_matrix(a), dense_to_csc(a)
    assert y.shape == x.shape
    np.testing.assert_array_equal(y.indptr, x.indptr)
    np.testing.assert_array_equal(y.indices, x.indices)
    np.testing.assert_array_equal(y.data, x.data)


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
    from models.robots import get_hand

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
    from models.robots import get_hand

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


def test_cell_members_are_each_cells_samples(box):
    """The winding number's near field walks each near cell's own samples (no padding): every sample once."""
    _, pts, nrm = box
    cloud = PointCloudField(pts, nrm)
    cells = cloud._cells()
    pick = np.array([3, 0, 3, len(cells.count) - 1])
    j, pair = cells.members(pick)
    assert len(j) == cells.count[pick].sum()
    for k, c in enumerate(pick):
        mine = j[pair == k]
        np.testing.assert_array_equal(mine, np.arange(cells.start[c], cells.start[c] + cells.count[c]))
    # the samples sorted by cell hold every sample exactly once
    assert sorted(map(tuple, np.round(cells.points, 12))) == sorted(map(tuple, np.round(pts, 12)))
