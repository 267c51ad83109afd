"""Objects met before: their geometry built once and kept for the next requests about them.

A worker meets the same object many times: a batch asks one object with several motions, hands or seeds, and a
planner asks again about the object it is holding. What `manifoundation.core.pipeline.prepare` derives from the object
alone — the processed mesh with its collision BVH, sharp edges and closest-point structures
(`manifoundation.core.geometry.per_mesh`),
the point field with its k-d trees, grown hull, winding-number cells and sample areas, the normals and the mass
properties — depends on nothing else in the request, so it is kept here, keyed by a digest of the bytes it was
built from, and shared by every request that sends the same bytes. The answers are those of a fresh build (the
shared structures are built the same way and only read); only the time changes.

Two levels: meshes by their vertices and faces (requests with other samples of the same mesh share its
structures), and prepared objects by points, normals, mask and mesh. Both are bounded in count and in estimated
bytes (least recently used out).
"""

from __future__ import annotations

import hashlib
import threading
from collections import OrderedDict
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Generic, TypeVar

import numpy as np
import trimesh

from manifoundation.core.geometry.object import MassProperties, ObjectGeometry
from manifoundation.core.refine.field import PointCloudField
from manifoundation.core.refine.volume import points_mass_properties

T = TypeVar("T")

MAX_ENTRIES = 8
"""Objects, and meshes, kept at most."""
MAX_BYTES = 16 * 2**20
"""Estimated bytes of the objects kept, and of the meshes (`object_bytes`, `mesh_bytes`): with both full a worker
holds ≈ 32 MB more, whatever objects come; an object larger than this alone is built and not kept."""
BYTES_PER_POINT = 260
"""A point of the field with its normal, k-d tree, sample area and winding cells (2 048 points: 0.5 MB, measured
with tracemalloc)."""
BYTES_PER_FACE = 700
"""A mesh face with its share of vertices, closest-point structures, pseudo-normals, sharp edges and BVH (a
9 216-face mesh: 5.6 MB by tracemalloc, which does not see the BVH's ≈ 100 bytes a face)."""


def digest(*arrays: np.ndarray | None) -> bytes:
    """A 16-byte digest of the arrays' dtypes, shapes and bytes (None counts as absent, distinct from empty)."""
    h = hashlib.blake2b(digest_size=16)
    for a in arrays:
        if a is None:
            h.update(b"\x00none")
            continue
        arr = np.ascontiguousarray(a)
        h.update(f"\x01{arr.dtype.str}{arr.shape}".encode())
        if arr.size:  # (an empty view cannot be cast)
            h.update(arr.data.cast("B"))
    return h.digest()


class LeastRecentlyUsed(Generic[T]):
    """A bounded map of built values: ``get(key, build)`` returns the kept value or keeps ``build()``'s, within
    ``max_entries`` and ``max_bytes`` (``size(value)``, estimated) — the least recently used go first; a value
    larger than ``max_bytes`` is returned and not kept.

    Thread-safe; a build runs outside the lock (two threads may build the same key; one value is kept)."""

    def __init__(self, max_entries: int, max_bytes: int = MAX_BYTES, size: Callable[[T], int] = lambda v: 0) -> None:
        self.max_entries, self.max_bytes, self.size = max_entries, max_bytes, size
        self._items: OrderedDict[bytes, tuple[T, int]] = OrderedDict()
        self._lock = threading.Lock()
        self.bytes = 0
        self.hits = 0
        self.misses = 0

    def get(self, key: bytes, build: Callable[[], T]) -> T:
        with self._lock:
            if key in self._items:
                self._items.move_to_end(key)
                self.hits += 1
                return self._items[key][0]
            self.misses += 1
        value = build()
        cost = self.size(value)
        if cost > self.max_bytes:
            return value
        with self._lock:
            if key in self._items:  # another thread kept it meanwhile
                return self._items[key][0]
            self._items[key] = (value, cost)
            self.bytes += cost
            while len(self._items) > self.max_entries or self.bytes > self.max_bytes:
                self.bytes -= self._items.popitem(last=False)[1][1]
        return value

    def __len__(self) -> int:
        return len(self._items)

    def clear(self) -> None:
        with self._lock:
            self._items.clear()
            self.bytes = self.hits = self.misses = 0


@dataclass
class PreparedObject:
    """What one object's bytes determine: its processed ``mesh`` (or None), the geometry with normals, the mesh
    used as the exact surface (``exact``: the mesh when watertight), the point field, and mass properties by
    density."""

    mesh: trimesh.Trimesh | None
    geometry: ObjectGeometry
    exact: trimesh.Trimesh | None
    cloud: PointCloudField
    masses: dict[float, MassProperties] = field(default_factory=dict)

    def mass_properties(self, density: float) -> MassProperties:
        """Mass, centre and inertia at ``density`` (kg/m³): of the exact mesh when there is one, else of the
        points' surface; computed once per density."""
        if density not in self.masses:
            self.masses[density] = (self.geometry.mass_properties(density) if self.exact is not None
                                    else points_mass_properties(self.cloud, density))  # fmt: skip
        return self.masses[density]


def object_bytes(obj: PreparedObject) -> int:
    """Estimated bytes of a prepared object (`BYTES_PER_POINT` per distance point) with its mesh, which it keeps
    alive even when the mesh cache has let it go."""
    points = len(obj.cloud.points) + (len(obj.cloud.surface.points) if obj.cloud.surface is not None else 0)
    return BYTES_PER_POINT * points + (mesh_bytes(obj.mesh) if obj.mesh is not None else 0)


def mesh_bytes(mesh: trimesh.Trimesh) -> int:
    """Estimated bytes of a mesh with the structures built on it (`BYTES_PER_FACE` per face)."""
    return BYTES_PER_FACE * len(mesh.faces)


class ObjectCache:
    """Meshes and prepared objects of the last requests (`MAX_ENTRIES`, `MAX_BYTES` each); ``enabled=False``
    builds every request afresh."""

    def __init__(self, max_entries: int = MAX_ENTRIES, max_bytes: int = MAX_BYTES, enabled: bool = True) -> None:
        self.objects: LeastRecentlyUsed[PreparedObject] = LeastRecentlyUsed(max_entries, max_bytes, object_bytes)
        self.meshes: LeastRecentlyUsed[trimesh.Trimesh] = LeastRecentlyUsed(max_entries, max_bytes, mesh_bytes)
        self.enabled = enabled

    def mesh(self, key: bytes, vertices: np.ndarray, faces: np.ndarray) -> trimesh.Trimesh:
        """The processed mesh of ``vertices`` (V, 3) float64 and ``faces`` (F, 3) int64 (trimesh merges
        duplicate vertices and drops degenerate faces), kept with the structures built on it; ``key``: their
        `digest`."""

        def build() -> trimesh.Trimesh:
            return trimesh.Trimesh(vertices=vertices.copy(), faces=faces.copy(), process=True)

        return self.meshes.get(key, build) if self.enabled else build()

    def prepared(self, key: bytes, build: Callable[[], PreparedObject]) -> PreparedObject:
        """The prepared object of ``key`` (`digest` of everything ``build`` reads), built once."""
        return self.objects.get(key, build) if self.enabled else build()

    def clear(self) -> None:
        self.objects.clear()
        self.meshes.clear()


default_cache = ObjectCache()
"""The process's cache, used by `manifoundation.core.pipeline.prepare.prepare` unless given another."""
