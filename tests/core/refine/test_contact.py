"""The contact model on the real fingertip surfaces, checked against the meshes' own vertices (independent)."""

import numpy as np
import pytest
import torch

from manifoundation.core.refine.contact import surface_contacts
from manifoundation.core.refine.state import HandPose


class HalfSpace:
    """The object {x : n·x ≤ h} (outward normal n): Φ(x) = n·x − h, exact for any point."""

    def __init__(self, normal: np.ndarray, offset: float) -> None:
        self.n, self.h = normal / np.linalg.norm(normal), offset

    def signed_distance(self, x):
        phi = x @ self.n - self.h
        return phi, np.tile(self.n, (len(x), 1)), x - phi[:, None] * self.n

    def given_normal(self, x):
        return np.tile(self.n, (len(x), 1))


def _rest(hand):
    return HandPose(np.zeros(3), np.array([1.0, 0, 0, 0]), np.asarray(hand.rest, dtype=np.float64))


def _body_vertices(hand, pose, body):
    with torch.no_grad():
        T = hand.link_poses(*pose.tensors())[body][0].numpy()
    v = np.asarray(hand.collision_meshes[body].vertices)
    return v @ T[:3, :3].T + T[:3, 3]


@pytest.mark.parametrize("name", ["leap", "allegro", "panda_gripper"])
def test_gap_is_the_fingertip_meshs_distance_to_the_object(name):
    """Below a plane, the distance of a mesh to it is its lowest vertex's: the sampled contact reads it within
    0.5 mm for every fingertip (the old sphere model read the sphere cover, 3-14 mm outside the mesh)."""
    from manifoundation.core.robots import get_hand

    hand = get_hand(name)
    pose = _rest(hand)
    from manifoundation.core.robots.pads import PAD_RADIUS

    with torch.no_grad():
        tips = hand.fingertips(*pose.tensors())[0].numpy()
    rng = np.random.default_rng(0)
    compared = 0
    for _ in range(12):
        n = rng.normal(size=3)
        n /= np.linalg.norm(n)
        for i, body in enumerate(hand.fingertip_bodies):
            verts = _body_vertices(hand, pose, body)
            extreme = verts[np.argmax(verts @ n)]
            if np.linalg.norm(extreme - tips[i]) > 0.8 * PAD_RADIUS:
                continue  # the mesh's extreme point along n is off the pad: another part would touch first
            plane = HalfSpace(-n, -float(extreme @ n) - 0.004)  # the object starts 4 mm beyond it
            found = surface_contacts(hand, pose.tensors(), plane, jacobian=False)
            exact = float(plane.signed_distance(verts)[0].min())
            assert exact == pytest.approx(0.004, abs=1e-9)
            assert abs(found.gap[i] - exact) < 5e-4, (name, i, found.gap[i], exact)
            compared += 1
    assert compared >= 3


def test_contact_jacobian_matches_finite_differences():
    from manifoundation.core.robots import get_hand

    hand = get_hand("allegro")
    pose = _rest(hand)
    plane = HalfSpace(np.array([1.0, 0.0, 0.0]), 0.1)
    found = surface_contacts(hand, pose.tensors(), plane)
    assert found.jac is not None
    rng = np.random.default_rng(1)
    delta = rng.normal(size=6 + hand.dof) * 1e-6
    moved = pose.step(hand, delta)
    with torch.no_grad():
        world = hand.surface_samples(*moved.tensors(), index=found.sample, jacobian=False)[0][0].numpy()
    predicted = found.points + np.einsum("man,n->ma", found.jac, delta)
    assert np.allclose(world, predicted, atol=1e-10)


def test_guards_see_a_fingertip_pushed_into_the_object():
    """A plane cutting 3 mm into a fingertip body: the guard rows hold a clearance of about −3 mm."""
    from manifoundation.core.refine.state import linearise
    from manifoundation.core.refine.wrench import closure_task
    from manifoundation.core.robots import get_hand

    hand = get_hand("leap")
    pose = _rest(hand)
    body = hand.fingertip_bodies[1]
    verts = _body_vertices(hand, pose, body)
    n = np.array([0.0, 0.0, -1.0])
    extreme = float((verts @ n).max())
    plane = HalfSpace(-n, -(extreme - 0.003))  # the object {n·x ≥ extreme − 3 mm}: the tip reaches 3 mm in

    class Field(HalfSpace):
        points = np.zeros((1, 3))

        def normal_jacobian(self, x):
            return np.zeros((len(x), 3, 3))

    field = Field(plane.n, plane.h)
    lin = linearise(hand, pose, field, closure_task(np.zeros(3), 0.05), 0.8, 10.0)
    exact = float(field.signed_distance(verts)[0].min())
    assert exact == pytest.approx(-0.003, abs=1e-9)
    assert lin.clear.min() == pytest.approx(exact, abs=1e-3)
    assert lin.penetration().max() > 0.002


def test_object_points_inside_a_fingertip_are_guarded():
    """An object point 2 mm inside a finger's face (between the surface samples) reads 2 mm deep on the
    finger's convex parts, from the mesh's own faces (not the samples)."""
    from manifoundation.core.refine.contact import GUARD_STANDOFF
    from manifoundation.core.refine.state import linearise
    from manifoundation.core.refine.wrench import closure_task
    from manifoundation.core.robots import get_hand

    hand = get_hand("panda_gripper")
    pose = _rest(hand)
    body = hand.fingertip_bodies[0]
    parts = hand.collision_meshes[body].split(only_watertight=False)
    mesh = max(parts, key=lambda m: m.convex_hull.volume).convex_hull  # the finger's largest part
    with torch.no_grad():
        T = hand.link_poses(*pose.tensors())[body][0].numpy()
    face = int(np.argmax(mesh.area_faces))
    inside = mesh.triangles_center[face] - 0.002 * mesh.face_normals[face]
    depth = float(-np.max(mesh.face_normals @ inside - np.einsum("ij,ij->i", mesh.face_normals,
                                                                    mesh.triangles_center)))  # fmt: skip
    point = T[:3, :3] @ inside + T[:3, 3]

    class Poke(HalfSpace):  # a plane clear of the finger (5 cm from its centre), and one point inside it
        points = point[None]

        def normal_jacobian(self, x):
            return np.zeros((len(x), 3, 3))

    centre = T[:3, :3] @ hand.collision_meshes[body].bounds.mean(0) + T[:3, 3]
    field = Poke(np.array([0.0, 0.0, -1.0]), -(float(centre[2]) + 0.05))  # beyond the fingertips, along +z
    lin = linearise(hand, pose, field, closure_task(np.zeros(3), 0.05), 0.8, 10.0)
    assert depth == pytest.approx(0.002, abs=2e-4)
    assert lin.clear.min() == pytest.approx(-depth - GUARD_STANDOFF, abs=1e-6)
