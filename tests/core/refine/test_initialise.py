import numpy as np
from scipy.spatial.transform import Rotation

from manifoundation.core.refine.field import PointCloudField
from manifoundation.core.refine.initialise import fit_palm, initialise, iou, rest_geometry, touch_overlap


def test_fit_recovers_a_known_palm_pose(gripper):
    rest = rest_geometry(gripper)
    rot = Rotation.from_rotvec([0.3, -0.2, 0.5]).as_matrix()
    t = np.array([0.1, -0.05, 0.2])
    contacts = rest.tips @ rot.T + t
    approach = rot @ gripper.approach_axis
    r_fit, t_fit, rms = fit_palm(rest.tips, contacts, gripper.approach_axis, approach, 0.5)
    assert rms < 1e-9
    np.testing.assert_allclose(r_fit, rot, atol=1e-8)
    np.testing.assert_allclose(t_fit, t, atol=1e-9)


def test_initialise_ranks_assignments_by_heatmap_iou(box):
    from manifoundation.core.robots import get_hand

    hand = get_hand("allegro")
    _, pts, nrm = box
    field = PointCloudField(pts, nrm)
    idx = [0, 300, 600, 900]
    cands = initialise(hand, field, pts[idx], nrm[idx], top_k=3)
    assert len(cands) == 3
    assert cands[0].iou >= cands[1].iou >= cands[2].iou
    assert sorted(cands[0].assignment) == sorted(set(cands[0].assignment))
    assert iou(np.array([1, 1, 0], bool), np.array([1, 0, 0], bool)) == 0.5


def test_touch_overlap_counts_each_touched_point_once(box):
    """The IoU counts of `touch_overlap` equal a brute-force count over every point's distance to every fingertip,
    for fingertips far apart (disjoint balls: summed counts) and close together (overlapping balls)."""
    _, pts, nrm = box
    field = PointCloudField(pts, nrm)
    rng = np.random.default_rng(3)
    far = pts[rng.choice(len(pts), size=(6, 3))] + rng.normal(scale=0.004, size=(6, 3, 3))
    close = pts[rng.choice(len(pts), size=(6, 1))] + rng.normal(scale=0.006, size=(6, 3, 3))
    tips = np.concatenate([far, close])  # (12, 3 fingertips, 3)
    target = np.linalg.norm(pts - pts[17], axis=1) < 0.02
    for radius in (0.005, 0.015):
        inter, union = touch_overlap(field, tips, target, radius)
        d = np.linalg.norm(pts[None, None] - tips[:, :, None], axis=-1)  # (F, m, N)
        touched = (d <= radius).any(axis=1)
        np.testing.assert_array_equal(inter, (touched & target).sum(axis=1))
        np.testing.assert_array_equal(union, (touched | target).sum(axis=1))
    assert touched[6:].sum() > 0 and (union > target.sum()).any()


def test_back_off_finds_the_first_clear_shift(box):
    """The back-off (which measures the spheres that blocked last time first) stops at the shift the plain rule
    gives: the first step at which every non-fingertip sphere is clear of the object."""
    from manifoundation.core.refine.initialise import back_off
    from manifoundation.core.robots import get_hand

    hand = get_hand("leap")
    _, pts, nrm = box
    field = PointCloudField(pts, nrm)
    rest = rest_geometry(hand)
    radii = np.asarray(hand.sphere_radii)
    body = ~rest.tip_sphere
    centre = pts.mean(axis=0)
    rng = np.random.default_rng(3)
    moved = 0
    for _ in range(6):
        rot = Rotation.random(random_state=rng).as_matrix()
        direction = rot @ np.asarray(hand.approach_axis, dtype=np.float64)
        t = centre - rot @ rest.tips.mean(axis=0)  # the hand's fingertips centred on the box: the palm is inside
        expected = t - direction * 0.1
        for k in range(int(0.1 / 0.005) + 1):  # the plain rule: every sphere measured at every shift
            shift = -direction * 0.005 * k
            if np.all(field.signed_distance(rest.spheres[body] @ rot.T + t + shift)[0] >= radii[body]):
                expected = t + shift
                break
        found = back_off(rot, t, rest, radii, field, direction)
        np.testing.assert_array_equal(found, expected)
        moved += int(np.linalg.norm(found - t) > 0)
    assert moved >= 3  # most starts needed backing off, so the shortcut was exercised
