"""The hand's hull meshes as MuJoCo mesh files, so MuJoCo's asset cache builds each hull once per process.

MuJoCo computes a mesh geom's convex hull (qhull) and its inertia every time a model is compiled — for LEAP's 103
convex pieces (34 305 hull vertices) 0.17 s of a scene's 0.2 s, paid by every request the physics test runs. A mesh
given by *file* is kept, processed, in MuJoCo's process-wide asset cache, so the next compile of a scene with the
same hand takes it from there (LEAP: 0.17 → 0.02 s). The files are MuJoCo's binary ``.msh`` with vertices only:
the same float32 vertices as ``uservert``, so the compiled model is bit-identical (its vertices, hull graphs,
inertias and geom sizes compared in `tests/core/physics/test_hull_files.py`). Named by their content, in one
directory per user, written atomically: processes share them and never see half a file.
"""

from __future__ import annotations

import hashlib
import os
import tempfile

import numpy as np

_directory: str | None = None


def hull_directory() -> str:
    """This user's directory of hull files (created on first use; a private one if the shared name is taken by
    another user)."""
    global _directory
    if _directory is None:
        path = os.path.join(tempfile.gettempdir(), f"manifoundation-hulls-{os.getuid()}")
        try:
            os.makedirs(path, mode=0o700, exist_ok=True)
            ours = os.stat(path).st_uid == os.getuid()
        except OSError:
            ours = False
        _directory = path if ours else tempfile.mkdtemp(prefix="manifoundation-hulls-")
    return _directory


def hull_file(vertices: np.ndarray) -> str:
    """The path of a ``.msh`` file holding ``vertices`` (k, 3) as float32 (written once; its name is its
    content's hash)."""
    v = np.ascontiguousarray(vertices, dtype="<f4").reshape(-1, 3)
    data = np.array([len(v), 0, 0, 0], dtype="<i4").tobytes() + v.tobytes()
    path = os.path.join(hull_directory(), hashlib.sha256(data).hexdigest()[:32] + ".msh")
    if not os.path.exists(path):
        fd, partial = tempfile.mkstemp(dir=hull_directory(), suffix=".part")
        with os.fdopen(fd, "wb") as out:
            out.write(data)
        os.replace(partial, path)
    return path
