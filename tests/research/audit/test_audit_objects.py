"""Third-party object meshes, concave test shapes, and the audit on them."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from research.audit import (
    AuditedGrasp,
    audit_grasp,
    concave_test_shapes,
    load_hand,
    sample_surface,
    third_party_objects,
)
from research.audit.hands import site_packages
from research.audit.penetration import measure_penetration

ROOT_OF_REPO = site_packages().parents[3]  # .venv/lib/python3.11/site-packages → the checkout
IDENTITY_Q = np.array([1.0, 0.0, 0.0, 0.0])
PAD_Z = 0.0584 + 0.04525


@pytest.fixture(scope="module")
def objects() -> list:
    return third_party_objects()


def test_third_party_objects_are_watertight_graspable_and_not_ours(objects: list) -> None:
    assert len(objects) >= 10
    assert len({o.name for o in objects}) == len(objects)
    for o in objects:
        assert o.path.is_relative_to(site_packages())
        assert o.mesh.is_watertight and o.mesh.is_winding_consistent and o.mesh.volume > 0
        assert float(o.mesh.extents.max()) == pytest.approx(0.08)
        np.testing.assert_allclose(o.mesh.bounds.mean(axis=0), 0.0, atol=1e-9)
    assert sum(o.solidity < 0.8 for o in objects) >= 4  # handles, drawer, cabinets: non-convex
    assert [o.name for o in third_party_objects(3)] == [o.name for o in objects[:3]]
    assert float(third_party_objects(1, size=0.05)[0].mesh.extents.max()) == pytest.approx(0.05)


def test_surface_samples_are_seeded_and_their_normals_point_out(objects: list) -> None:
    obj = objects[0]
    p1, n1 = obj.sample(500, seed=4)
    p2, n2 = obj.sample(500, seed=4)
    np.testing.assert_array_equal(p1, p2)
    np.testing.assert_array_equal(n1, n2)
    assert not np.array_equal(p1, obj.sample(500, seed=5)[0])
    np.testing.assert_allclose(np.linalg.norm(n1, axis=1), 1.0)
    assert not obj.mesh.contains(p1 + 2e-4 * n1).any()
    assert obj.mesh.contains(p1 - 2e-4 * n1).mean() > 0.95  # thin features may be thinner than 0.2 mm


def test_concave_test_shapes_are_watertight_and_concave() -> None:
    shapes = concave_test_shapes()
    assert set(shapes) == {"cup_with_handle", "mug", "torus", "l_shape"}
    for name, mesh in shapes.items():
        assert mesh.is_watertight and mesh.is_winding_consistent and mesh.volume > 0, name
        assert 0.04 <= float(mesh.extents.max()) <= 0.12, name
        assert mesh.volume / mesh.convex_hull.volume < 0.7, name
    assert shapes["l_shape"].volume == pytest.approx(0.03 * (0.08 * 0.02 + 0.02 * 0.04))
    points, normals = sample_surface(shapes["mug"], 2000, seed=0)
    assert not shapes["mug"].contains(points + 1e-4 * normals).any()  # the handle's gap keeps inside tests exact


def test_finger_through_a_torus_hole_does_not_penetrate_but_its_hull_would() -> None:
    hand = load_hand("panda_gripper")
    q, _, _ = hand.joint_values(["panda_finger_joint1"], [0.03])
    poses = hand.link_poses(np.zeros(3), IDENTITY_Q, q)
    torus = concave_test_shapes()["torus"]  # axis z, hole radius 2 cm
    torus.apply_translation([0.0, 0.03 + 7.58e-3, PAD_Z])  # around the left finger's pad
    exact = measure_penetration(hand.links, poses, torus)
    assert "panda_leftfinger" in exact.tested_links and exact.depth == 0.0
    hull = measure_penetration(hand.links, poses, torus.convex_hull)
    assert hull.depth > 5e-3 and hull.link == "panda_leftfinger"


@pytest.mark.parametrize(("squeeze", "passes"), [(0.0, True), (3e-3, False)])
def test_panda_on_the_gymnasium_egg(objects: list, squeeze: float, passes: bool) -> None:
    egg = next(o for o in objects if o.name == "egg").mesh.copy()  # semi-axes 3, 3, 4 cm
    egg.apply_transform(trimesh.transformations.rotation_matrix(np.pi / 2, [0, 1, 0]))  # long axis along x
    egg.apply_translation([0.0, 0.0, PAD_Z])  # its bottom then clears the hand body
    radius = float(egg.extents[1] / 2)
    opening = radius - (7.58e-3 - 7.6e-3) - squeeze  # pad inner faces at y = ±(radius − squeeze)
    points = np.array([[0.0, radius, PAD_Z], [0.0, -radius, PAD_Z]])
    forces = np.array([[0.0, -2.0, 0.5], [0.0, 2.0, 0.5]])
    grasp = AuditedGrasp(
        points, forces, ["panda_leftfinger", "panda_rightfinger"], np.zeros(3), IDENTITY_Q,
        ["panda_finger_joint1"], np.array([opening]),
    )  # fmt: skip
    report = audit_grasp("panda_gripper", grasp, egg, mu=0.5, target_wrench=[0, 0, 1, 0, 0, 0])
    assert report.target_cosine == pytest.approx(1.0)
    assert report.passed is passes, report.failures
    assert report.penetration is not None
    assert report.penetration.depth == pytest.approx(squeeze, abs=2e-4)


def test_repo_meshes_are_not_among_the_third_party_objects(objects: list) -> None:
    ours = (ROOT_OF_REPO / "models").resolve()
    assert all(not o.path.resolve().is_relative_to(ours) for o in objects)
    assert isinstance(objects[0].mesh, trimesh.Trimesh)
