"""Collision spheres cover each link's collision mesh; self-collision pairs exclude adjacent links."""

from __future__ import annotations

import numpy as np
import pytest
import torch
import trimesh

from manifoundation.core.robots import get_hand, list_hands
from manifoundation.core.robots.spheres import MARGIN

COVER_TOL = 1e-3
"""Fresh surface samples must lie within this distance of (inside) some sphere of their own link."""


@pytest.mark.parametrize("name", list_hands())
def test_spheres_cover_collision_meshes(name: str) -> None:
    hand = get_hand(name)
    links = np.asarray(hand.sphere_links)
    for link, mesh in hand.collision_meshes.items():
        pts, _ = trimesh.sample.sample_surface(mesh, 2000, seed=123)
        sel = links == link
        c, r = hand.sphere_centres[sel], hand.sphere_radii[sel]
        assert len(r) > 0, f"{name}: link {link} has no spheres"
        gap = (np.linalg.norm(pts[:, None] - c[None], axis=-1) - r[None]).min(axis=1)
        assert gap.max() < COVER_TOL, f"{name}/{link}: a point lies {gap.max() * 1e3:.2f} mm outside"
    assert MARGIN <= COVER_TOL


@pytest.mark.parametrize("name", list_hands())
def test_self_collision_pairs_are_clear_at_rest_and_skip_adjacent(name: str) -> None:
    hand = get_hand(name)
    P = hand.self_collision_pairs
    if len(P) == 0:
        return
    links = np.asarray(hand.sphere_links)
    assert np.all(links[P[:, 0]] != links[P[:, 1]])
    tree = hand.tree
    bodies = {n: i for i, n in enumerate(tree.body_names)}
    for a, b in P:
        ba, bb = bodies[links[a]], bodies[links[b]]
        assert tree.parent[ba] != bb and tree.parent[bb] != ba
    d = torch.float64
    ct, _ = hand.spheres(torch.zeros(1, 3, dtype=d), torch.tensor([[1.0, 0, 0, 0]], dtype=d),
                        torch.as_tensor(hand.rest[None]), jacobian=False)  # fmt: skip
    c = ct[0].numpy()
    dist = np.linalg.norm(c[P[:, 0]] - c[P[:, 1]], axis=1)
    assert np.all(dist >= hand.sphere_radii[P[:, 0]] + hand.sphere_radii[P[:, 1]])


@pytest.mark.parametrize("name", list_hands())
def test_surface_normals_point_outward(name: str) -> None:
    """Stepping 1 mm against the normal lands inside the hand (some body's convex hull) for nearly all points."""
    hand = get_hand(name)
    d = torch.float64
    poses = hand.link_poses(torch.zeros(1, 3, dtype=d), torch.tensor([[1.0, 0, 0, 0]], dtype=d),
                            torch.as_tensor(hand.rest[None]))  # fmt: skip
    inner = hand.surface_points - 1e-3 * hand.surface_normals
    inside = np.zeros(len(inner), dtype=bool)
    for link, mesh in hand.collision_meshes.items():
        T = poses[link][0].numpy()
        hull = mesh.convex_hull
        local = (inner - T[:3, 3]) @ T[:3, :3]
        slack = np.einsum("ij,ij->i", hull.face_normals, hull.triangles_center)[None] - local @ hull.face_normals.T
        inside |= slack.min(axis=1) > 0
    assert inside.mean() > 0.95, f"{name}: only {inside.mean():.1%} of inward steps land inside the hand"


@pytest.mark.parametrize("name", list_hands())
def test_fingertip_points_lie_on_the_collision_surface(name: str) -> None:
    """Tip offsets are pad points: within 2 mm of their link's collision mesh surface."""
    hand = get_hand(name)
    d = torch.float64
    poses = hand.link_poses(torch.zeros(1, 3, dtype=d), torch.tensor([[1.0, 0, 0, 0]], dtype=d),
                            torch.as_tensor(hand.rest[None]))  # fmt: skip
    tips = hand.fingertips(torch.zeros(1, 3, dtype=d), torch.tensor([[1.0, 0, 0, 0]], dtype=d),
                           torch.as_tensor(hand.rest[None]))[0].numpy()  # fmt: skip
    meshes = []
    for link, mesh in hand.collision_meshes.items():
        m = mesh.copy()
        m.apply_transform(poses[link][0].numpy())
        meshes.append(m)
    union = trimesh.util.concatenate(meshes)
    _, dist, _ = trimesh.proximity.closest_point(union, tips)
    assert dist.max() < 2e-3, f"{name}: tip points {np.round(dist * 1e3, 2)} mm from the surface"
