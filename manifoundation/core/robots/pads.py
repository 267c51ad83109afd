"""Fingertip contact surfaces: evenly spaced samples of each fingertip body's real collision mesh.

A fingertip touches the object with its real surface, not with a sphere fitted around it: the fitted spheres reach
9-12 mm outside the meshes, so contacts judged on them left the fingers short of the object. Each fingertip body's
mesh (its link with fixed children merged in) is sampled evenly every ``SAMPLE_SPACING`` (Poisson-disc, seed 0,
plus the mesh vertices, deduplicated), each sample with its outward face normal. Samples within ``PAD_RADIUS`` of
the fingertip's tip point form its *pad*: the places the contact may be. All of a fingertip body's samples guard
it against penetrating the object (they replace that body's spheres in the non-penetration rows; spheres stay for
the other bodies and for self-collision, where a conservative cover is right).

Accuracy: where a convex finger surface of curvature radius R faces the object, the nearest sample lies at most
s/√3 ≈ 1.4 mm (s = spacing) beside the touching point and so reads the gap at most s²/(6R) high: 0.1 mm for
R = 8 mm. Verification does not rely on the samples: it measures on the meshes (`manifoundation.core.refine.verify`).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np
import trimesh
from scipy.spatial import cKDTree

SAMPLE_SPACING = 2.5e-3
"""m: Poisson-disc spacing of the samples."""
PAD_RADIUS = 0.02
"""m: samples this close to the tip point are candidate contact points."""
MAX_SAMPLES_PER_BODY = 2000


@dataclass(frozen=True)
class ContactSurface:
    """Samples of the fingertip bodies' surfaces (K samples in all), in their body frames.

    Attributes:
        body: (K,) body index (into ``KinematicTree.body_names``) carrying each sample.
        local: (K, 3) positions in the body frame.
        normals: (K, 3) outward unit normals in the body frame.
        fingertip: (K,) index of the fingertip whose body carries the sample.
        pad: (K,) bool, the sample may carry the fingertip's contact (within ``PAD_RADIUS`` of the tip point).
        tip_distance: (K,) each sample's distance to its fingertip's tip point (ties between pad samples equally
            near the object, e.g. a flat pad on a flat face, go to the one nearest the tip point).
        link: (K,) name of the link (of the body's merged links) each sample lies on ("" when unknown).
        bound_centre, bound_radius: (m, 3) body-frame centre and (m,) radius of a sphere around each fingertip's
            samples (cheap culling before distance queries).
    """

    body: np.ndarray
    local: np.ndarray
    normals: np.ndarray
    fingertip: np.ndarray
    pad: np.ndarray
    tip_distance: np.ndarray
    link: np.ndarray
    bound_centre: np.ndarray
    bound_radius: np.ndarray

    def __len__(self) -> int:
        return len(self.body)

    def pads(self, fingertip: int) -> np.ndarray:
        """Indices of fingertip ``fingertip``'s pad samples."""
        return np.flatnonzero(self.pad & (self.fingertip == fingertip))


def sample_evenly(mesh: trimesh.Trimesh, spacing: float) -> tuple[np.ndarray, np.ndarray]:
    """Evenly spaced surface samples (k, 3) of ``mesh`` and their face normals (k, 3), deterministic.

    Poisson-disc samples (``trimesh.sample.sample_surface_even``) plus the mesh's vertices (corners and edges that
    area sampling misses) with the mean normal of their faces, the vertices thinned to half the spacing.
    """
    area = float(mesh.area)
    count = int(np.clip(2.0 * area / spacing**2, 16, 4 * MAX_SAMPLES_PER_BODY))
    quiet = logging.getLogger("trimesh")
    level = quiet.level
    quiet.setLevel(logging.ERROR)  # "only got k/n samples": expected, the disc radius decides the count
    try:
        pts, faces = trimesh.sample.sample_surface_even(mesh, count, radius=spacing, seed=0)
    finally:
        quiet.setLevel(level)
    nrm = np.asarray(mesh.face_normals)[faces]
    verts = np.asarray(mesh.vertices)
    vnorm = np.asarray(mesh.vertex_normals)
    keep = _thin(verts, 0.5 * spacing)  # a polyhedron's extreme points are vertices: keep them (thinned)
    pts = np.vstack([pts, verts[keep]])
    nrm = np.vstack([nrm, vnorm[keep]])
    if len(pts) > MAX_SAMPLES_PER_BODY:
        pick = np.random.default_rng(0).choice(len(pts), MAX_SAMPLES_PER_BODY, replace=False)
        pts, nrm = pts[np.sort(pick)], nrm[np.sort(pick)]
    nrm = nrm / np.maximum(np.linalg.norm(nrm, axis=1, keepdims=True), 1e-12)
    return pts, nrm


def _thin(points: np.ndarray, spacing: float) -> np.ndarray:
    """Indices of a subset of ``points`` with no two closer than ``spacing`` (greedy, in order)."""
    if not len(points):
        return np.zeros(0, dtype=np.int64)
    tree = cKDTree(points)
    taken = np.zeros(len(points), dtype=bool)
    blocked = np.zeros(len(points), dtype=bool)
    for i in range(len(points)):
        if blocked[i]:
            continue
        taken[i] = True
        blocked[tree.query_ball_point(points[i], spacing)] = True
    return np.flatnonzero(taken)


def build_contact_surface(
    body_meshes: dict[int, trimesh.Trimesh], tip_body: np.ndarray, tip_local: np.ndarray,
    spacing: float = SAMPLE_SPACING, pad_radius: float = PAD_RADIUS,
    link_meshes: list[dict[str, trimesh.Trimesh]] | None = None,
) -> ContactSurface:  # fmt: skip
    """Sample every fingertip body (see module doc).

    Args:
        body_meshes: body index -> mesh in that body's frame, for (at least) the fingertip bodies.
        tip_body: (m,) body index of each fingertip; tip_local: (m, 3) its tip point in the body frame.
        spacing: sample spacing (m). pad_radius: pad extent around the tip point (m).
        link_meshes: per fingertip, the geometry of each link of its body (link name -> mesh, body frame): each
            sample is labelled with the link it lies on (a body merges fixed children into its link: Allegro's
            fingertip link is the 12 mm tip sphere on the distal phalanx link), so a contact names its link.
    """
    body, local, normals, owner, pad, reach, labels = [], [], [], [], [], [], []
    centres, radii = [], []
    for i, (b, tip) in enumerate(zip(tip_body, tip_local, strict=True)):
        mesh = body_meshes.get(int(b))
        if mesh is None or len(mesh.faces) == 0:
            pts, nrm = np.asarray(tip, dtype=np.float64)[None], np.zeros((1, 3))
        else:
            pts, nrm = sample_evenly(mesh, spacing)
        near = np.linalg.norm(pts - tip, axis=1) <= pad_radius
        parts = link_meshes[i] if link_meshes is not None else {}
        names = list(parts) or [""]
        if len(names) > 1:
            gaps = np.stack([np.abs(trimesh.proximity.ProximityQuery(m).signed_distance(pts)) for m in parts.values()])
            which = np.argmin(gaps, axis=0)
        else:
            which = np.zeros(len(pts), dtype=np.int64)
        labels.append(np.asarray([names[k] for k in which], dtype=object))
        if not near.any():  # a tip point far from its mesh: the nearest samples are the pad
            near = np.linalg.norm(pts - tip, axis=1) <= np.linalg.norm(pts - tip, axis=1).min() + pad_radius
        body.append(np.full(len(pts), int(b)))
        local.append(pts)
        normals.append(nrm)
        owner.append(np.full(len(pts), i))
        pad.append(near)
        reach.append(np.linalg.norm(pts - tip, axis=1))
        lo, hi = pts.min(0), pts.max(0)
        centres.append(0.5 * (lo + hi))
        radii.append(float(np.linalg.norm(pts - 0.5 * (lo + hi), axis=1).max()))
    return ContactSurface(
        body=np.concatenate(body).astype(np.int64),
        local=np.vstack(local),
        normals=np.vstack(normals),
        fingertip=np.concatenate(owner).astype(np.int64),
        pad=np.concatenate(pad),
        tip_distance=np.concatenate(reach),
        link=np.concatenate(labels),
        bound_centre=np.asarray(centres),
        bound_radius=np.asarray(radii),
    )


def convex_parts(mesh: trimesh.Trimesh) -> list[tuple[np.ndarray, np.ndarray]]:
    """Half-spaces (f, 4) ``n·x ≤ d`` and bounds (2, 3) of the convex hull of each connected part of ``mesh``: a
    body merges several links' shapes (LEAP: a convex hull per visual mesh), and the hull of their union reached
    2 mm beyond them."""
    parts = mesh.split(only_watertight=False) if len(mesh.faces) else []
    pieces = [m for m in parts if len(m.faces) >= 4] or [mesh]
    out = []
    for piece in pieces:
        try:
            hull = piece.convex_hull
        except Exception:  # a flat or degenerate piece has no hull volume: it cannot contain a point
            continue
        n = np.asarray(hull.face_normals)
        d = np.einsum("ij,ij->i", n, np.asarray(hull.triangles_center))
        out.append((np.hstack([n, d[:, None]]), np.asarray(piece.bounds)))
    return out
