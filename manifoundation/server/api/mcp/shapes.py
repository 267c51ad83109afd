"""Primitive objects an agent can name instead of sending points: a box, a sphere, a cylinder (numpy only).

Each is centred on its frame's origin (a cylinder's axis along z), with area-uniform surface points, their exact
outward normals and a closed triangle mesh (so collisions and verification use the exact surface). Seeded: the
same shape and count give the same points.
"""

from __future__ import annotations

from typing import Literal

import numpy as np

from manifoundation.contract import MeshIn, ObjectIn, PhysicalProperties

Shape = Literal["box", "sphere", "cylinder"]
SEGMENTS = 32


def _box(size: np.ndarray, n: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray, MeshIn]:
    half = size / 2
    areas = np.array([size[1] * size[2], size[0] * size[2], size[0] * size[1]] * 2)
    face = rng.choice(6, size=n, p=areas / areas.sum())
    axis, sign = face % 3, np.where(face < 3, 1.0, -1.0)
    points = (rng.random((n, 3)) * 2 - 1) * half
    points[np.arange(n), axis] = sign * half[axis]
    normals = np.zeros((n, 3))
    normals[np.arange(n), axis] = sign
    corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], dtype=np.float64) * half
    faces = [[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
             [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]]  # fmt: skip
    return points, normals, MeshIn(vertices=corners, faces=np.array(faces))


def _sphere(radius: float, n: int) -> tuple[np.ndarray, np.ndarray, MeshIn]:
    i = np.arange(n) + 0.5
    polar, azimuth = np.arccos(1 - 2 * i / n), np.pi * (1 + 5**0.5) * i
    normals = np.stack([np.cos(azimuth) * np.sin(polar), np.sin(azimuth) * np.sin(polar), np.cos(polar)], axis=1)
    rings = SEGMENTS // 2
    theta = np.linspace(0, np.pi, rings + 1)[1:-1]
    phi = np.linspace(0, 2 * np.pi, SEGMENTS, endpoint=False)
    ring = np.stack([np.outer(np.sin(theta), np.cos(phi)), np.outer(np.sin(theta), np.sin(phi)),
                     np.repeat(np.cos(theta)[:, None], SEGMENTS, axis=1)], axis=2).reshape(-1, 3)  # fmt: skip
    vertices = np.vstack([[0, 0, 1], ring, [0, 0, -1]]) * radius
    faces, last = [], len(vertices) - 1
    for b in range(SEGMENTS):
        c = (b + 1) % SEGMENTS
        faces.append([0, 1 + b, 1 + c])
        faces.append([last, 1 + (rings - 2) * SEGMENTS + c, 1 + (rings - 2) * SEGMENTS + b])
        for a in range(rings - 2):
            p, q = 1 + a * SEGMENTS, 1 + (a + 1) * SEGMENTS
            faces += [[p + b, q + b, q + c], [p + b, q + c, p + c]]
    return normals * radius, normals, MeshIn(vertices=vertices, faces=np.array(faces))


def _cylinder(radius: float, height: float, n: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray, MeshIn]:
    side, cap = 2 * np.pi * radius * height, np.pi * radius**2
    part = rng.choice(3, size=n, p=np.array([side, cap, cap]) / (side + 2 * cap))
    angle = rng.random(n) * 2 * np.pi
    r = np.where(part == 0, radius, radius * np.sqrt(rng.random(n)))
    z = np.where(part == 0, (rng.random(n) - 0.5) * height, np.where(part == 1, height / 2, -height / 2))
    points = np.stack([r * np.cos(angle), r * np.sin(angle), z], axis=1)
    normals = np.where((part == 0)[:, None], np.stack([np.cos(angle), np.sin(angle), np.zeros(n)], axis=1),
                       np.stack([np.zeros(n), np.zeros(n), np.where(part == 1, 1.0, -1.0)], axis=1))  # fmt: skip
    phi = np.linspace(0, 2 * np.pi, SEGMENTS, endpoint=False)
    rim = np.stack([radius * np.cos(phi), radius * np.sin(phi)], axis=1)
    top, bottom = 2 + np.arange(SEGMENTS), 2 + SEGMENTS + np.arange(SEGMENTS)
    vertices = np.vstack([[0, 0, height / 2], [0, 0, -height / 2], np.c_[rim, np.full(SEGMENTS, height / 2)],
                          np.c_[rim, np.full(SEGMENTS, -height / 2)]])  # fmt: skip
    faces = []
    for b in range(SEGMENTS):
        c = (b + 1) % SEGMENTS
        faces += [[0, top[b], top[c]], [1, bottom[c], bottom[b]], [top[b], bottom[b], bottom[c]],
                  [top[b], bottom[c], top[c]]]  # fmt: skip
    return points, normals, MeshIn(vertices=vertices, faces=np.array(faces))


def primitive(shape: Shape, size: list[float], num_points: int = 1024, friction: float | None = None,
              seed: int = 0) -> ObjectIn:  # fmt: skip
    """A primitive object.

    Args:
        shape: ``"box"`` (``size`` = [x, y, z] full extents, m), ``"sphere"`` ([radius]) or ``"cylinder"``
            ([radius, height], axis along z).
        num_points: surface points (64 ≤ N ≤ 200 000, checked by the contract).
        friction: Coulomb μ (the contract's default when None).

    Raises:
        ValueError: ``size`` has the wrong length or a non-positive entry (the message names ``size``).
    """
    want = {"box": 3, "sphere": 1, "cylinder": 2}[shape]
    dims = np.asarray(size, dtype=np.float64).reshape(-1)
    if len(dims) != want or not np.all(np.isfinite(dims)) or np.any(dims <= 0):
        raise ValueError(f"size: a {shape} takes {want} positive number(s) (metres), got {list(size)}")
    rng = np.random.default_rng(seed)
    if shape == "box":
        points, normals, mesh = _box(dims, num_points, rng)
    elif shape == "sphere":
        points, normals, mesh = _sphere(float(dims[0]), num_points)
    else:
        points, normals, mesh = _cylinder(float(dims[0]), float(dims[1]), num_points, rng)
    properties = PhysicalProperties() if friction is None else PhysicalProperties(friction=friction)
    return ObjectIn(points=points, normals=normals, mesh=mesh, properties=properties)
