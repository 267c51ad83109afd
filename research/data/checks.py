"""Exact-enough rejection tests for sampled hands: hand–object penetration and self-collision.

Penetration: points sampled on every collision mesh of the hand (posed by forward kinematics) are tested
against the object: a KD-tree point-to-plane distance on a dense oriented cloud flags candidates, and the
flagged points are confirmed with the mesh's exact signed distance (trimesh). A hand is rejected when any
point lies deeper than ``PENETRATION_TOL`` inside the object. When `manifoundation.core.geometry` provides
``hand_object_penetration`` / ``hand_self_collision`` those are used instead (see `sampling.py`).
These are fast pre-filters; `sampling.exact_checks` then applies the verification's own tests (fcl).
Self-collision: the hand's self-collision sphere pairs may not overlap by more than ``PENETRATION_TOL``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
import torch
import trimesh
from scipy.spatial import cKDTree

if TYPE_CHECKING:
    from manifoundation.core.robots.hand import Hand

PENETRATION_TOL = 1e-3  # m (DESIGN §5)
HAND_SAMPLES_PER_BODY = 96
DENSE_POINTS = 8192


@dataclass
class ObjectField:
    """An object's mesh with a dense oriented cloud for fast distance queries."""

    mesh: trimesh.Trimesh
    seed: int = 0
    points: np.ndarray = field(init=False)
    normals: np.ndarray = field(init=False)
    tree: cKDTree = field(init=False)

    def __post_init__(self) -> None:
        pts, faces = trimesh.sample.sample_surface(self.mesh, DENSE_POINTS, seed=self.seed)
        self.points = np.asarray(pts, dtype=np.float64)
        self.normals = np.asarray(self.mesh.face_normals, dtype=np.float64)[faces]
        self.tree = cKDTree(self.points)

    def signed_distance(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Φ (M,) point-to-plane, outward normal (M, 3), nearest cloud point (M, 3)."""
        _, idx = self.tree.query(np.asarray(x, dtype=np.float64))
        near, nrm = self.points[idx], self.normals[idx]
        phi: np.ndarray = np.einsum("ij,ij->i", x - near, nrm)
        return phi, nrm, near

    def nearest(self, x: np.ndarray) -> np.ndarray:
        """Projection of x onto the local tangent plane of the nearest cloud point (≈ closest surface point)."""
        phi, nrm, _ = self.signed_distance(x)
        projected: np.ndarray = x - phi[:, None] * nrm
        return projected

    def surface(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Nearest surface points (M, 3) (tangent-plane projection) and outward normals (M, 3)."""
        phi, nrm, _ = self.signed_distance(x)
        return x - phi[:, None] * nrm, nrm

    def exact_signed_distance(self, x: np.ndarray) -> np.ndarray:
        """Mesh signed distance, positive *outside* (trimesh's sign flipped)."""
        return -np.asarray(trimesh.proximity.signed_distance(self.mesh, np.asarray(x, dtype=np.float64)))


_HAND_SAMPLES: dict[str, list[tuple[str, np.ndarray]]] = {}


def hand_samples(hand: Hand) -> list[tuple[str, np.ndarray]]:
    """(body link, (S, 3) points in the link frame) for every collision mesh (cached per hand name)."""
    if hand.name not in _HAND_SAMPLES:
        out = []
        for i, (link, mesh) in enumerate(hand.collision_meshes.items()):
            pts, _ = trimesh.sample.sample_surface(mesh, HAND_SAMPLES_PER_BODY, seed=i)
            verts = np.asarray(mesh.vertices)[:: max(1, len(mesh.vertices) // 64)]
            out.append((link, np.vstack([np.asarray(pts), verts])))
        _HAND_SAMPLES[hand.name] = out
    return _HAND_SAMPLES[hand.name]


def penetration_depth(
    hand: Hand,
    obj: ObjectField,
    palm_pos: torch.Tensor,
    palm_quat: torch.Tensor,
    q: torch.Tensor,
    skip: frozenset[str] = frozenset(),
) -> np.ndarray:
    """Deepest penetration (B,) ≥ 0 of the hand's collision geometry (bodies not in ``skip``) into the object."""
    poses = hand.link_poses(palm_pos, palm_quat, q)
    world = []
    for link, local in hand_samples(hand):
        if link in skip:
            continue
        T = poses[link].numpy()  # (B, 4, 4)
        world.append(np.einsum("bij,sj->bsi", T[:, :3, :3], local) + T[:, None, :3, 3])
    if not world:
        return np.zeros(palm_pos.shape[0])
    pts = np.concatenate(world, axis=1)  # (B, S, 3)
    B, S = pts.shape[:2]
    phi, _, _ = obj.signed_distance(pts.reshape(-1, 3))
    phi = phi.reshape(B, S)
    depth = np.zeros(B)
    flagged = phi < -PENETRATION_TOL
    for b in np.flatnonzero(flagged.any(axis=1)):
        cand = pts[b][flagged[b]]
        # the deepest few candidates decide; confirm with the exact mesh distance
        order = np.argsort(phi[b][flagged[b]])[:32]
        exact = obj.exact_signed_distance(cand[order])
        depth[b] = max(0.0, float(-exact.min()))
    return depth


def fingertip_bodies(hand: Hand) -> frozenset[str]:
    """Names of the bodies that carry fingertips."""
    return frozenset(hand.tree.body_names[hand.tree.link_body[link][0]] for link in hand.fingertip_links)


def self_overlap(hand: Hand, palm_pos: torch.Tensor, palm_quat: torch.Tensor, q: torch.Tensor) -> np.ndarray:
    """Largest overlap (B,) ≥ 0 of the hand's self-collision sphere pairs (m)."""
    pairs = np.asarray(hand.self_collision_pairs, dtype=np.int64).reshape(-1, 2)
    if not len(pairs):
        return np.zeros(palm_pos.shape[0])
    centres, _ = hand.spheres(palm_pos, palm_quat, q, jacobian=False)
    c = centres.numpy()
    r = np.asarray(hand.sphere_radii)
    dist = np.linalg.norm(c[:, pairs[:, 0]] - c[:, pairs[:, 1]], axis=-1)
    overlap: np.ndarray = np.clip(r[pairs].sum(axis=1)[None] - dist, 0.0, None).max(axis=1)
    return overlap
