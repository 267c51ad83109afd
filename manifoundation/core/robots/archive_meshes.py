"""Mesh files of an uploaded archive, loaded from its bytes with vertex and face caps.

Each mesh is parsed by trimesh from the member's bytes (``file_type`` from the suffix: STL, OBJ, DAE through
pycollada) with no resolver, so a mesh naming a texture or material file cannot make it open anything. A mesh with
more than ``MAX_MESH_FACES`` faces or ``MAX_MESH_VERTICES`` vertices, or all of them together more than
``MAX_TOTAL_FACES``, is refused naming the member. Each member is parsed once (links sharing a file share it).
"""

from __future__ import annotations

import io
import logging

import numpy as np
import trimesh

from manifoundation.core.errors import HandLoadError
from manifoundation.core.robots.archive import MAX_MESH_FACES, MESH_SUFFIXES, HandArchive
from manifoundation.core.robots.urdf import MeshLoader

MAX_MESH_VERTICES = 500_000
MAX_TOTAL_FACES = 2_000_000


class ArchiveMeshes:
    """Loads the archive's meshes on demand (``loader(base)`` gives a URDF :data:`MeshLoader`).

    Attributes:
        loaded: member name → faces, for the meshes read so far.
    """

    def __init__(self, archive: HandArchive) -> None:
        self.archive = archive
        self.loaded: dict[str, int] = {}
        self._cache: dict[str, trimesh.Trimesh] = {}

    def mesh(self, member: str) -> trimesh.Trimesh:
        """The mesh of ``member`` (checked against the caps; cached).

        Raises:
            HandLoadError: unknown suffix, unreadable, empty or over a cap.
        """
        if member in self._cache:
            return self._cache[member]
        suffix = member.rsplit(".", 1)[-1].lower()
        if f".{suffix}" not in MESH_SUFFIXES:
            raise HandLoadError(f"mesh {member!r}: unsupported format .{suffix} (use {', '.join(MESH_SUFFIXES)})")
        _check_declared_size(member, suffix, self.archive.files[member])
        quiet = logging.getLogger("trimesh")
        level = quiet.level
        quiet.setLevel(logging.ERROR)
        try:
            loaded = trimesh.load(io.BytesIO(self.archive.files[member]), file_type=suffix, force="mesh", process=False)
        except Exception as e:  # any parser failure of untrusted bytes is the caller's malformed file
            raise HandLoadError(f"mesh {member!r}: unreadable {suffix.upper()} ({type(e).__name__}: {e})") from e
        finally:
            quiet.setLevel(level)
        if not isinstance(loaded, trimesh.Trimesh) or len(loaded.faces) == 0:
            raise HandLoadError(f"mesh {member!r}: no triangles")
        faces, verts = len(loaded.faces), len(loaded.vertices)
        _check_caps(member, faces, verts)
        if not np.all(np.isfinite(loaded.vertices)):
            raise HandLoadError(f"mesh {member!r}: non-finite vertex coordinates")
        self.loaded[member] = faces
        if sum(self.loaded.values()) > MAX_TOTAL_FACES:
            raise HandLoadError(f"meshes: more than {MAX_TOTAL_FACES} faces in all (at {member!r})")
        self._cache[member] = loaded
        return loaded

    def loader(self, base: str) -> MeshLoader:
        """A URDF mesh loader resolving names against the archive folder ``base`` (see `HandArchive.resolve`)."""

        def load(filename: str, scale: np.ndarray) -> trimesh.Trimesh | None:
            mesh = self.mesh(self.archive.resolve(filename, base)).copy()
            mesh.apply_scale(scale)
            return mesh

        return load


def _check_declared_size(member: str, suffix: str, data: bytes) -> None:
    """Refuse a text mesh whose face or vertex count is over the caps before a parser builds it: an OBJ's ``f`` and
    ``v`` lines, an ASCII STL's facets, counted on the bytes (a 1.2 M-face OBJ took seconds to parse before its size
    was known). Binary STLs are checked from their header when the archive is read; COLLADA is parsed as XML."""
    if suffix == "obj":
        faces = data.count(b"\nf ") + data.startswith(b"f ")
        verts = data.count(b"\nv ") + data.startswith(b"v ")
    elif suffix == "stl" and data[:5].lower() == b"solid":
        faces = data.count(b"facet normal")
        verts = 3 * faces
    else:
        return
    _check_caps(member, faces, verts)


def _check_caps(member: str, faces: int, verts: int) -> None:
    """Refuse a mesh over the face or vertex cap, naming the member and the counts."""
    if faces > MAX_MESH_FACES or verts > MAX_MESH_VERTICES:
        raise HandLoadError(
            f"mesh {member!r}: {faces} faces / {verts} vertices, over the {MAX_MESH_FACES} / {MAX_MESH_VERTICES} limit"
        )
