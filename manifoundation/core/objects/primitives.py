"""Mesh constructors for the procedural objects (all watertight, in metres, not yet centred or scaled)."""

from __future__ import annotations

import numpy as np
import trimesh

_SPHERE_SUBDIVISIONS = 4  # 2562 vertices: radial meshes keep edges to ~1/40 of the size


def box(rng: np.random.Generator) -> trimesh.Trimesh:
    """A box with aspect ratios in [0.3, 1]."""
    mesh: trimesh.Trimesh = trimesh.creation.box(extents=rng.uniform(0.3, 1.0, size=3))
    return mesh


def cylinder(rng: np.random.Generator) -> trimesh.Trimesh:
    """A cylinder with radius/height ratio in [0.15, 0.8]."""
    mesh: trimesh.Trimesh = trimesh.creation.cylinder(radius=rng.uniform(0.15, 0.8) * 0.5, height=1.0, sections=48)
    return mesh


def sphere(rng: np.random.Generator) -> trimesh.Trimesh:
    """A unit sphere (the seed only names it)."""
    mesh: trimesh.Trimesh = trimesh.creation.icosphere(subdivisions=_SPHERE_SUBDIVISIONS, radius=0.5)
    return mesh


def capsule(rng: np.random.Generator) -> trimesh.Trimesh:
    """A capsule with radius/length ratio in [0.15, 0.45]."""
    radius = rng.uniform(0.15, 0.45) * 0.5
    mesh: trimesh.Trimesh = trimesh.creation.capsule(height=1.0 - 2 * radius, radius=radius, count=[24, 24])
    return mesh


def ellipsoid(rng: np.random.Generator) -> trimesh.Trimesh:
    """An ellipsoid with semi-axis ratios in [0.35, 1]."""
    mesh: trimesh.Trimesh = trimesh.creation.icosphere(subdivisions=_SPHERE_SUBDIVISIONS, radius=1.0)
    mesh.apply_scale(rng.uniform(0.35, 1.0, size=3))
    return mesh


def convex(rng: np.random.Generator) -> trimesh.Trimesh:
    """Convex hull of 12-40 random points on a random ellipsoid."""
    d = rng.normal(size=(int(rng.integers(12, 41)), 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    hull: trimesh.Trimesh = trimesh.convex.convex_hull(d * rng.uniform(0.4, 1.0, size=3))
    return hull


def _halfspaces(mesh: trimesh.Trimesh) -> tuple[np.ndarray, np.ndarray]:
    """Face normals N and offsets b of a convex mesh: inside is N x <= b."""
    normals = np.asarray(mesh.face_normals)
    offsets = np.einsum("ij,ij->i", normals, mesh.triangles[:, 0])
    return normals, offsets


def radial_union(parts: list[trimesh.Trimesh], subdivisions: int = _SPHERE_SUBDIVISIONS) -> trimesh.Trimesh:
    """Union of convex parts that all contain the origin, as a watertight radial mesh.

    A union of sets that are star-shaped about the origin is star-shaped, and its radial function is the maximum
    of the parts' ones; for a convex part the ray x = t d leaves at t = min over faces with n·d > 0 of b / n·d.

    Args:
        parts: convex meshes, each containing the origin strictly.
        subdivisions: icosphere subdivisions of the direction grid.

    Returns:
        The union (exact at the grid directions).
    """
    grid = trimesh.creation.icosphere(subdivisions=subdivisions, radius=1.0)
    dirs = np.asarray(grid.vertices)
    radius = np.zeros(len(dirs))
    for part in parts:
        normals, offsets = _halfspaces(part)
        if np.any(offsets <= 0):
            raise ValueError("every part must contain the origin")
        nd = dirs @ normals.T
        with np.errstate(divide="ignore"):
            t = np.where(nd > 1e-12, offsets[None, :] / np.where(nd > 1e-12, nd, 1.0), np.inf)
        radius = np.maximum(radius, t.min(axis=1))
    return trimesh.Trimesh(vertices=dirs * radius[:, None], faces=grid.faces, process=True)


def composite(rng: np.random.Generator) -> trimesh.Trimesh:
    """Non-convex union of 2-4 boxes/cylinders/ellipsoids, offset but each containing the origin."""
    makers = (box, cylinder, ellipsoid)
    parts = []
    for _ in range(int(rng.integers(2, 5))):
        part = makers[int(rng.integers(len(makers)))](rng)
        rot = trimesh.transformations.random_rotation_matrix(rng.uniform(size=3))
        part.apply_transform(rot)
        part = part.convex_hull
        # Offset by up to 80 % of the inradius about the origin, so the origin stays strictly inside.
        direction = rng.normal(size=3)
        inradius = float(_halfspaces(part)[1].min())
        part.apply_translation(direction / np.linalg.norm(direction) * rng.uniform(0.3, 0.8) * inradius)
        parts.append(part)
    return radial_union(parts)


def blob(rng: np.random.Generator) -> trimesh.Trimesh:
    """Non-convex star-shaped body: radius 1 + a few random low-frequency bumps and dents."""
    grid = trimesh.creation.icosphere(subdivisions=_SPHERE_SUBDIVISIONS, radius=1.0)
    dirs = np.asarray(grid.vertices)
    radius = np.ones(len(dirs))
    for _ in range(int(rng.integers(3, 7))):
        centre = rng.normal(size=3)
        centre /= np.linalg.norm(centre)
        width = rng.uniform(0.4, 0.9)
        radius += rng.uniform(-0.35, 0.35) * np.exp(-(1.0 - dirs @ centre) / (width**2 / 2))
    radius = np.clip(radius, 0.4, None)
    return trimesh.Trimesh(vertices=dirs * radius[:, None] * rng.uniform(0.5, 1.0, size=3), faces=grid.faces)


CONSTRUCTORS = {
    "box": box,
    "cylinder": cylinder,
    "sphere": sphere,
    "capsule": capsule,
    "ellipsoid": ellipsoid,
    "convex": convex,
    "composite": composite,
    "blob": blob,
}
