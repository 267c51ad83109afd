"""`audit_grasp` catches what it should, on configurations posed with the audit's own kinematics."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from research.audit import AuditedGrasp, audit_grasp, closure_epsilon, load_hand, pose_matrix

OPENING = 0.03  # panda_finger_joint1
PAD_Z = 0.0584 + 0.04525  # finger joint origin + rubber pad centre, palm frame
PAD_FACE = OPENING + 7.58e-3 - 15.2e-3 / 2  # inner face of the left pad (|y|), palm frame
BOX_X, BOX_Z = 0.04, 0.04
IDENTITY_Q = np.array([1.0, 0.0, 0.0, 0.0])
LEFT_RIGHT = ["panda_leftfinger", "panda_rightfinger"]
PADS = load_hand("panda_gripper", prefer="collision")
"""The Panda with its URDF's collision boxes (the rubber pads' known faces) for these checks of the audit's logic;
its default geometry is the real finger mesh (`test_visual_geometry_can_be_preferred`)."""


def _box(half_y: float) -> trimesh.Trimesh:
    box = trimesh.creation.box(extents=[BOX_X, 2 * half_y, BOX_Z])
    box.apply_translation([0.0, 0.0, PAD_Z])
    return box


def _panda_grasp(half_y: float, forces: np.ndarray | None = None, opening: float = OPENING) -> AuditedGrasp:
    points = np.array([[0.0, half_y, PAD_Z], [0.0, -half_y, PAD_Z]])
    f = np.array([[0.0, -1.0, 0.0], [0.0, 1.0, 0.0]]) if forces is None else forces
    return AuditedGrasp(points, f, LEFT_RIGHT, np.zeros(3), IDENTITY_Q, ["panda_finger_joint1"], np.array([opening]))


@pytest.mark.parametrize(("gap", "passes"), [(1e-3, True), (8e-3, False)])
def test_contact_distance_to_the_finger_surface(gap: float, passes: bool) -> None:
    half = PAD_FACE - gap  # box faces `gap` inside the pads: contacts on the box, `gap` from the fingers
    report = audit_grasp(PADS, _panda_grasp(half), _box(half), mu=0.5)
    np.testing.assert_allclose(report.finger_distances, gap, atol=1e-6)
    np.testing.assert_allclose(report.object_distances, 0.0, atol=1e-9)
    assert report.penetration is not None and report.penetration.depth == 0.0
    assert report.passed is passes
    assert any("from panda_leftfinger's surface" in f for f in report.failures) is not passes


def test_contact_off_the_object_surface_fails() -> None:
    half = PAD_FACE - 1e-3
    grasp = _panda_grasp(half)
    report = audit_grasp(PADS, grasp, _box(half - 7e-3), mu=0.5)  # object 7 mm smaller each side
    np.testing.assert_allclose(report.object_distances, 7e-3, atol=1e-9)
    assert any("from the object surface" in f for f in report.failures)


def test_penetration_of_three_millimetres_is_found_and_located() -> None:
    half = PAD_FACE + 3e-3
    report = audit_grasp(PADS, _panda_grasp(half), _box(half), mu=0.5)
    pen = report.penetration
    assert pen is not None
    assert pen.depth == pytest.approx(3e-3, abs=2e-4)
    assert pen.link in LEFT_RIGHT and pen.point is not None
    assert set(pen.per_link) >= set(LEFT_RIGHT) and min(pen.per_link[k] for k in LEFT_RIGHT) > 2.5e-3
    assert not report.passed and any("overlap by 3.0" in f for f in report.failures)
    # 0.5 mm in: within the 1 mm tolerance
    half = PAD_FACE + 5e-4
    report = audit_grasp(PADS, _panda_grasp(half), _box(half), mu=0.5)
    assert report.penetration is not None and report.penetration.depth == pytest.approx(5e-4, abs=1e-4)
    assert report.passed, report.failures


def test_penetration_of_the_palm_body_is_found() -> None:
    half = PAD_FACE - 1e-3
    box = trimesh.creation.box(extents=[BOX_X, 2 * half, 0.06])
    box.apply_translation([0.0, 0.0, PAD_Z - 0.01])  # reaches down to z = 0.0736: into the hand body's mesh
    report = audit_grasp(PADS, _panda_grasp(half), box, mu=0.5)
    assert report.penetration is not None and report.penetration.link == "panda_hand"
    assert report.penetration.depth > 1e-3 and not report.passed


def test_friction_cone_pulling_and_sliding_forces() -> None:
    half = PAD_FACE
    inside = np.array([[0.3, -1.0, 0.2], [0.0, 1.0, 0.0]])
    outside = np.array([[0.8, -1.0, 0.0], [0.0, 1.0, 0.0]])
    pulling = np.array([[0.0, 1.0, 0.0], [0.0, 1.0, 0.0]])
    ok = audit_grasp(PADS, _panda_grasp(half, inside), _box(half), mu=0.5)
    assert ok.passed, ok.failures
    np.testing.assert_allclose(ok.friction_ratios, [np.hypot(0.3, 0.2), 0.0], atol=1e-12)
    np.testing.assert_allclose(ok.normal_forces, [1.0, 1.0], atol=1e-12)
    slide = audit_grasp(PADS, _panda_grasp(half, outside), _box(half), mu=0.5)
    assert slide.friction_ratios[0] == pytest.approx(0.8)
    assert any("contact 0 leaves its friction cone" in f for f in slide.failures)
    pull = audit_grasp(PADS, _panda_grasp(half, pulling), _box(half), mu=0.5)
    assert pull.normal_forces[0] == pytest.approx(-1.0) and pull.normal_forces[1] == pytest.approx(1.0)
    assert [f for f in pull.failures if "pulls" in f] == ["contact 0 pulls the object (normal force -1 N)"]


def test_caller_normals_replace_the_mesh_normals() -> None:
    half = PAD_FACE
    box = _box(half)
    points = np.array([[0.0, half, PAD_Z], [0.0, -half, PAD_Z]])
    flipped = np.array([[0.0, -1.0, 0.0], [0.0, 1.0, 0.0]])  # inward normals: the pushing forces now pull
    report = audit_grasp(PADS, _panda_grasp(half), box, points, flipped, mu=0.5)
    np.testing.assert_allclose(report.normal_forces, [-1.0, -1.0])
    assert sum("pulls" in f for f in report.failures) == 2


def test_wrench_cosine_of_antipodal_forces() -> None:
    half, t = PAD_FACE, 0.3
    lift = np.array([[0.0, -1.0, t], [0.0, 1.0, t]])  # squeeze + lift: net force 2t along z, no torque
    up = audit_grasp(PADS, _panda_grasp(half, lift), _box(half), mu=0.5, target_wrench=[0, 0, 1, 0, 0, 0])
    assert up.target_cosine == pytest.approx(1.0) and up.passed and up.wrench is not None
    np.testing.assert_allclose(up.wrench, np.array([0, 0, 2 * t, 0, 0, 0]), atol=1e-12)
    side = audit_grasp(PADS, _panda_grasp(half, lift), _box(half), mu=0.5, target_wrench=[1, 0, 0, 0, 0, 0])
    assert side.target_cosine == pytest.approx(0.0, abs=1e-12)
    assert any("wrench cosine" in f for f in side.failures)
    twist = np.array([[0.0, -1.0, t], [0.0, 1.0, -t]])  # torque 2·half·t about x
    report = audit_grasp(
        PADS, _panda_grasp(half, twist), _box(half), mu=0.5, target_wrench=[0, 0, 1, 1, 0, 0]
    )
    L = np.linalg.norm([BOX_X / 2, half, BOX_Z / 2])  # bounding-sphere radius about the box centre
    assert report.length == pytest.approx(L) and report.wrench is not None
    np.testing.assert_allclose(report.wrench, np.array([0, 0, 0, 2 * half * t / L, 0, 0]), atol=1e-12)
    assert report.target_cosine == pytest.approx(1 / np.sqrt(1 + L**2))  # target scaled to [F, τ / L]


def test_force_closure_needs_more_than_two_point_contacts() -> None:
    a, c, L = 0.03, 0.015, 0.05
    up, down = np.array([0.0, 1.0, 0.0]), np.array([0.0, -1.0, 0.0])
    two = np.array([[0, a, 0], [0, -a, 0]])
    assert closure_epsilon(two, np.array([up, down]), 0.8, np.zeros(3), L) == 0.0  # free to spin about y
    four = np.array([[0, a, c], [0, a, -c], [0, -a, c], [0, -a, -c]])
    normals = np.array([up, up, down, down])
    eps = closure_epsilon(four, normals, 0.8, np.zeros(3), L)
    assert eps > 1e-3
    assert closure_epsilon(four, normals, 0.1, np.zeros(3), L) < eps  # less friction, smaller margin
    same_face = np.array([[0.01, a, c], [-0.01, a, -c], [0.01, a, -c], [-0.01, a, c]])
    assert closure_epsilon(same_face, np.array([up] * 4), 0.8, np.zeros(3), L) == 0.0  # cannot pull


def test_closure_criterion_in_the_audit() -> None:
    half = PAD_FACE
    report = audit_grasp(PADS, _panda_grasp(half), _box(half), mu=0.8, closure=True)
    assert report.closure_epsilon == 0.0
    assert any("force closure" in f for f in report.failures)


def test_joint_problems_are_reported() -> None:
    half = PAD_FACE
    box = _box(half)
    grasp = _panda_grasp(half)
    bad = AuditedGrasp(**{**grasp.__dict__, "joint_names": ["panda_finger_joint1", "panda_finger_joint2"]})
    bad.joint_values = np.array([OPENING, OPENING - 0.01])
    assert any("coupling gives" in f for f in audit_grasp(PADS, bad, box, mu=0.5).failures)
    wide = audit_grasp(PADS, _panda_grasp(half, opening=0.05), box, mu=0.5)
    assert any("outside its limits" in f for f in wide.failures)
    unknown = AuditedGrasp(**{**grasp.__dict__, "joint_names": ["finger"]})
    assert not audit_grasp(PADS, unknown, box, mu=0.5).passed
    shadow = AuditedGrasp(
        grasp.contact_points, grasp.forces, ["robot0:ffdistal"] * 2, np.zeros(3), IDENTITY_Q, [], np.zeros(0)
    )
    report = audit_grasp("shadow", shadow, box, mu=0.5)
    assert any("neither reported nor derivable" in f for f in report.failures)


def test_the_audit_does_not_depend_on_the_world_frame() -> None:
    half = PAD_FACE + 2e-3
    grasp, box = _panda_grasp(half, np.array([[0.2, -1.0, 0.0], [0.0, 1.0, 0.1]])), _box(half)
    base = audit_grasp(PADS, grasp, box, mu=0.5, target_wrench=[0, 0, 1, 0, 0, 0])
    quat = np.array([0.3, -0.5, 0.7, 0.2]) / np.linalg.norm([0.3, -0.5, 0.7, 0.2])
    W = pose_matrix([0.4, -0.1, 0.25], quat)
    R, p = W[:3, :3], W[:3, 3]
    moved = AuditedGrasp(
        grasp.contact_points @ R.T + p, grasp.forces @ R.T, LEFT_RIGHT, p, quat, grasp.joint_names, grasp.joint_values
    )
    target = np.concatenate([R @ [0, 0, 1], np.zeros(3)])
    other = audit_grasp(PADS, moved, box.copy().apply_transform(W), mu=0.5, target_wrench=target)
    np.testing.assert_allclose(other.finger_distances, base.finger_distances, atol=1e-9)
    np.testing.assert_allclose(other.friction_ratios, base.friction_ratios, atol=1e-9)
    assert other.target_cosine == pytest.approx(base.target_cosine)
    assert base.penetration is not None and other.penetration is not None
    assert other.penetration.depth == pytest.approx(base.penetration.depth, abs=2e-4)
    assert base.penetration.depth == pytest.approx(2e-3, abs=2e-4)


def test_leap_visual_mesh_contact_distance() -> None:
    hand = load_hand("leap")
    q, _, _ = hand.joint_values([], [])
    q = dict.fromkeys(hand.kinematics.limits, 0.0)
    T = hand.link_poses(np.zeros(3), IDENTITY_Q, q)["tip_soft_2"]
    mesh = hand.links["tip_soft_2"].mesh
    k = int(np.argmax(np.asarray(mesh.vertices) @ [1.0, 0.0, 0.0]))  # the pad bulges towards link +x
    tip = T[:3, :3] @ mesh.vertices[k] + T[:3, 3]
    out = T[:3, :3] @ [1.0, 0.0, 0.0]
    for gap, passes in ((1e-3, True), (8e-3, False)):
        radius = 0.03
        ball = trimesh.creation.icosphere(subdivisions=4, radius=radius)
        ball.apply_translation(tip + (gap + radius) * out)
        contact = tip + gap * out
        grasp = AuditedGrasp(
            contact[None], out[None], ["tip_soft_2"], np.zeros(3), IDENTITY_Q, list(q), np.array(list(q.values()))
        )
        report = audit_grasp(hand, grasp, ball, mu=0.5, contact_tol=5e-3)
        assert report.finger_distances[0] == pytest.approx(gap, abs=1e-4)
        assert report.penetration is not None and report.penetration.depth < 1e-4
        assert report.passed is passes, report.failures


@pytest.mark.parametrize(
    ("hand_name", "link", "local_point", "offset_dir"),
    [
        ("allegro", "link_3.0_tip", [0.0, 0.0, 0.0], [np.sqrt(0.5), 0.0, np.sqrt(0.5)]),  # sphere r 12 mm
        ("shadow", "robot0:ffdistal", [0.0, -0.00705, 0.012], [0.0, -1.0, 0.0]),  # capsule r 7.05 mm at z 12 mm
        ("barrett", "bh_f1_distal", [0.0, -0.009, 0.02], [0.0, -1.0, 0.0]),  # box 18 mm deep
        ("kinova3f", "k3f_f1_distal", [0.0, -0.005, 0.022], [0.0, -1.0, 0.0]),  # box 10 mm deep
    ],
)
def test_fingertip_surface_distance_matches_the_description(
    hand_name: str, link: str, local_point: list[float], offset_dir: list[float]
) -> None:
    hand = load_hand(hand_name)
    rng = np.random.default_rng(0)
    free = [j for j in hand.kinematics.limits if j not in {c.joint for c in hand.kinematics.couplings}]
    values = [float(rng.uniform(*np.clip(hand.kinematics.limits[j], -1.0, 1.0))) for j in free]
    q, missing, _ = hand.joint_values(free, values)
    assert not missing
    quat = np.array([0.5, 0.5, -0.5, 0.5])
    T = hand.link_poses(np.array([0.2, 0.1, -0.3]), quat, q)[link]
    if hand_name == "allegro":
        local_point = list(0.012 * np.asarray(offset_dir))
    for gap in (1e-3, 8e-3):
        p = T[:3, :3] @ (np.asarray(local_point) + gap * np.asarray(offset_dir)) + T[:3, 3]
        n = T[:3, :3] @ offset_dir  # the object's outward normal faces the finger
        grasp = AuditedGrasp(p[None], -n[None], [link], np.array([0.2, 0.1, -0.3]), quat, free, np.array(values))
        report = audit_grasp(hand, grasp, None, p[None], n[None], mu=0.5)
        assert report.finger_distances[0] == pytest.approx(gap, abs=5e-5)
        assert report.passed is (gap < 5e-3), report.failures
        assert "no object mesh: penetration not measured" in report.notes


def test_malformed_proposals_fail() -> None:
    half = PAD_FACE
    grasp = _panda_grasp(half)
    fields = {**grasp.__dict__, "palm_quaternion": [2.0, 0.0, 0.0, 0.0]}
    report = audit_grasp(PADS, AuditedGrasp.from_mapping(fields), _box(half), mu=0.5)
    assert any("not a unit quaternion" in f for f in report.failures)
    fields = {**grasp.__dict__, "forces": [[np.nan, 0, 0], [0, 1, 0]], "extra": 1}
    report = audit_grasp(PADS, AuditedGrasp.from_mapping(fields), _box(half), mu=0.5)
    assert not report.passed and "non-finite" in report.failures[0]
    ok = audit_grasp(PADS, AuditedGrasp.from_mapping(grasp.__dict__), _box(half), mu=0.5)
    assert ok.passed, ok.failures


def test_visual_geometry_can_be_preferred() -> None:
    collision, visual = load_hand("allegro", prefer="collision"), load_hand("allegro", prefer="visual")
    tip = "link_3.0_tip"
    assert collision.links[tip].source == "collision" and visual.links[tip].source == "visual"
    # the default: a link drawn only through primitives around a visual mesh is judged on the mesh (Allegro's
    # boxes and tip spheres, the Panda's finger boxes), a link colliding through meshes keeps them (the Panda's hand)
    assert all(g.source == "visual" for g in load_hand("allegro").links.values())
    panda = load_hand("panda_gripper")
    assert panda.links["panda_leftfinger"].source == "visual" and panda.links["panda_hand"].source == "collision"
    assert len(collision.links[tip].pieces) == 1 and len(visual.links[tip].mesh.faces) == 1438  # link_3.0_tip.STL
    # the URDF's collision sphere (r 12 mm, on the link origin) and the STL (its base is cut flat at z = -11 mm)
    point = np.array([[0.0, 0.0, -0.0125]])
    d_sphere = trimesh.proximity.closest_point(collision.links[tip].mesh, point)[1][0]
    assert d_sphere == pytest.approx(5e-4, abs=5e-5)
    assert trimesh.proximity.closest_point(visual.links[tip].mesh, point)[1][0] == pytest.approx(1.5e-3, abs=1e-6)
    assert load_hand("barrett", prefer="visual").links["bh_f1_distal"].source == "collision"  # no visuals there
    with pytest.raises(ValueError, match="prefer"):
        load_hand("kinova3f", prefer="mesh")
