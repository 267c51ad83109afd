"""Seeded procedural objects with ids, and the documented evaluation set."""

from __future__ import annotations

import hashlib
from dataclasses import dataclass

import numpy as np
import trimesh

from manifoundation.core.objects.primitives import CONSTRUCTORS

OBJECT_KINDS: tuple[str, ...] = tuple(CONSTRUCTORS)
DEFAULT_SIZE_RANGE = (0.05, 0.25)  # metres, largest bounding-box extent (data generation uses 0.05-0.40)


@dataclass(frozen=True)
class ProceduralObject:
    """A generated object, centred on its centre of mass (uniform density).

    Attributes:
        id: stable name, ``"{kind}-{8 hex digits}"`` derived from kind, size and seed.
        kind: one of `OBJECT_KINDS`.
        size: largest bounding-box extent (m).
        seed: the seed it was made from.
        mesh: watertight triangle mesh (m).
        points: (N, 3) points sampled on the surface (area-uniform).
        normals: (N, 3) outward unit normals at `points`.
    """

    id: str
    kind: str
    size: float
    seed: int
    mesh: trimesh.Trimesh
    points: np.ndarray
    normals: np.ndarray


def make_object(kind: str, size: float, seed: int, num_points: int = 2048) -> ProceduralObject:
    """Make one object.

    Args:
        kind: one of `OBJECT_KINDS`.
        size: largest bounding-box extent in metres.
        seed: seed for shape parameters and point sampling.
        num_points: surface points to sample.

    Returns:
        The object.

    Raises:
        ValueError: unknown kind or non-positive size.
    """
    if kind not in CONSTRUCTORS:
        raise ValueError(f"unknown object kind {kind!r}; choose from {', '.join(OBJECT_KINDS)}")
    if not size > 0:
        raise ValueError(f"size must be positive, got {size}")
    rng = np.random.default_rng(seed)
    mesh = CONSTRUCTORS[kind](rng)
    mesh.merge_vertices()
    mesh.fix_normals()
    if not mesh.is_watertight:
        raise RuntimeError(f"{kind} (seed {seed}) is not watertight")
    mesh.apply_scale(size / float(np.max(mesh.extents)))
    mesh.apply_translation(-np.asarray(mesh.center_mass))
    points, faces = trimesh.sample.sample_surface(mesh, num_points, seed=int(rng.integers(2**31)))
    normals = np.asarray(mesh.face_normals)[faces]
    digest = hashlib.sha1(f"{kind}:{size:.6f}:{seed}".encode()).hexdigest()[:8]
    return ProceduralObject(
        id=f"{kind}-{digest}",
        kind=kind,
        size=float(size),
        seed=int(seed),
        mesh=mesh,
        points=np.asarray(points, dtype=np.float64),
        normals=normals.astype(np.float64),
    )


def object_set(
    count: int,
    seed: int = 0,
    size_range: tuple[float, float] = DEFAULT_SIZE_RANGE,
    kinds: tuple[str, ...] = OBJECT_KINDS,
    num_points: int = 2048,
) -> list[ProceduralObject]:
    """The evaluation set: objects cycle through ``kinds``; sizes uniform in ``size_range``.

    Object ``i`` uses kind ``kinds[i % len(kinds)]`` and a seed drawn from ``seed``, so a set is a prefix of any
    larger set with the same seed.
    """
    objects = []
    for i in range(count):
        rng = np.random.default_rng([seed, i])
        size = float(rng.uniform(*size_range))
        objects.append(make_object(kinds[i % len(kinds)], size, int(rng.integers(2**31)), num_points))
    return objects
