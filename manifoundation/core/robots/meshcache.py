"""Convex hulls of a built-in's mesh files, cached as package data.

The ghand (LEAP-style) URDF draws 103 visual meshes with 1.2 M faces; loading them takes > 1 s and they are far
too fine for collision checks. We replace every mesh file by its convex hull, computed once by
:func:`build_hull_cache` and stored in ``descriptions/<name>_hulls.npz`` (a test regenerates it and compares).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import trimesh

from manifoundation.core.robots.urdf import MeshLoader


def build_hull_cache(mesh_dir: Path, out: Path) -> None:
    """Write the convex hull (vertices, faces) of every mesh file in ``mesh_dir`` to ``out`` (npz)."""
    arrays: dict[str, np.ndarray] = {}
    for path in sorted(mesh_dir.iterdir()):
        if path.suffix.lower() not in {".ply", ".stl", ".obj", ".dae"}:
            continue
        mesh = trimesh.load(str(path), force="mesh")
        hull = mesh.convex_hull  # type: ignore[attr-defined]
        arrays[f"{path.name}/v"] = np.asarray(hull.vertices, dtype=np.float64)
        arrays[f"{path.name}/f"] = np.asarray(hull.faces, dtype=np.int32)
    np.savez_compressed(out, **arrays)  # type: ignore[arg-type]


def hull_loader(cache: Path) -> MeshLoader:
    """A mesh loader that answers a filename with the cached hull of the file of the same base name."""
    data = dict(np.load(cache))

    def load(filename: str, scale: np.ndarray) -> trimesh.Trimesh | None:
        base = filename.replace("\\", "/").rsplit("/", 1)[-1]
        if f"{base}/v" not in data:
            return None
        mesh = trimesh.Trimesh(data[f"{base}/v"] * scale, data[f"{base}/f"], process=False)
        return mesh

    return load
