import numpy as np
from scipy.spatial.transform import Rotation

from models.refine.field import PointCloudField
from models.refine.initialise import fit_palm, initialise, iou, rest_geometry


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
    from models.robots import get_hand

    hand = get_hand("allegro")
    _, pts, nrm = box
    field = PointCloudField(pts, nrm)
    idx = [0, 300, 600, 900]
    cands = initialise(hand, field, pts[idx], nrm[idx], top_k=3)
    assert len(cands) == 3
    assert cands[0].iou >= cands[1].iou >= cands[2].iou
    assert sorted(cands[0].assignment) == sorted(set(cands[0].assignment))
    assert iou(np.array([1, 1, 0], bool), np.array([1, 0, 0], bool)) == 0.5
