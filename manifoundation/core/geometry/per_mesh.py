"""Structures built once per object mesh and kept on it: verification of K proposals, the refinement's mesh
contacts and the penetration test meet the same mesh many times (its triangles, BVH, sharp edges, pseudo-normals,
vertex tree)."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import trimesh


def per_mesh(mesh: trimesh.Trimesh, key: str, build: Callable[[], Any]) -> Any:
    """``build()`` once per ``mesh`` and ``key``, kept on the mesh and rebuilt when its data changes (trimesh's
    hash of it)."""
    cache = mesh.__dict__.setdefault("_mani_cache", {})
    stamp = hash(mesh)
    if key not in cache or cache[key][0] != stamp:
        cache[key] = (stamp, build())
    return cache[key][1]
