"""Objects from where users' data is: numpy arrays, trimesh meshes, files (.npz .ply .obj .stl .json).

Everything returns the contract's `ObjectIn`, validated on the spot, so a mistake names its field before
anything is sent. trimesh is imported only by the functions that read meshes.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np
import pydantic

from manifoundation.contract import MeshIn, ObjectIn
from manifoundation.sdk.errors import checked, local_validation_error
from manifoundation.sdk.extras import require

MESH_SUFFIXES = (".ply", ".obj", ".stl", ".off", ".glb")
DEFAULT_NUM_POINTS = 2048
# Meshes up to this many faces travel with the request (exact penetration checks); larger ones are left out.
MAX_MESH_FACES = 20_000

ObjectLike = ObjectIn | np.ndarray | str | os.PathLike[str] | dict[str, Any] | Any


def object_from_points(points: Any, normals: Any = None, **fields: Any) -> ObjectIn:
    """An object from an (N, 3) point array, or (N, 6) points with normals, metres.

    Args:
        points: (N, 3) points, or (N, 6) ``[x, y, z, nx, ny, nz]`` rows.
        normals: (N, 3) outward normals (normalised for you), when not in ``points``.
        **fields: other `ObjectIn` fields: ``material``, ``properties``, ``region_mask``, ``joint``, ``mesh``.
    """
    array = np.asarray(points, dtype=np.float64)
    if array.ndim == 2 and array.shape[1] == 6 and normals is None:
        array, normals = array[:, :3], array[:, 3:]
    return checked(ObjectIn, "object", points=array, normals=normals, **fields)


def object_from_mesh(
    mesh: Any,
    num_points: int = DEFAULT_NUM_POINTS,
    *,
    seed: int = 0,
    include_mesh: bool | None = None,
    **fields: Any,
) -> ObjectIn:
    """An object from a ``trimesh.Trimesh``: area-uniform surface points with their face normals.

    Args:
        mesh: a triangle mesh in metres (outward face normals, as trimesh gives them for closed meshes).
        num_points: points to sample (64 ≤ N ≤ 200 000).
        seed: sampling seed; the same seed gives the same points.
        include_mesh: send the mesh too, for exact collision checks (default: when it has at most
            `MAX_MESH_FACES` faces).
        **fields: other `ObjectIn` fields (``material``, ``properties``, ``region_mask``, ...).
    """
    trimesh = require("trimesh", "mesh", "a mesh as an object")

    if not isinstance(mesh, trimesh.Trimesh) or len(mesh.faces) == 0:
        raise TypeError(f"expected a trimesh.Trimesh with faces, got {type(mesh).__name__}")
    points, face_index = trimesh.sample.sample_surface(mesh, int(num_points), seed=seed)
    normals = np.asarray(mesh.face_normals)[face_index]
    if include_mesh is None:
        include_mesh = len(mesh.faces) <= MAX_MESH_FACES
    if include_mesh and "mesh" not in fields:
        fields["mesh"] = checked(
            MeshIn, "object.mesh", vertices=np.asarray(mesh.vertices), faces=np.asarray(mesh.faces)
        )
    return object_from_points(np.asarray(points), normals, **fields)


def object_from_file(
    path: str | os.PathLike[str], num_points: int = DEFAULT_NUM_POINTS, *, seed: int = 0, **fields: Any
) -> ObjectIn:
    """An object from a file: a mesh (``.ply``, ``.obj``, ``.stl``, ...), a ``.ply`` point cloud or an ``.npz``.

    An ``.npz`` holds ``points`` (N, 3) and optionally ``normals``, ``region_mask``, and ``vertices`` +
    ``faces`` (the mesh). A point-cloud ``.ply`` keeps its own points and normals (``nx``, ``ny``, ``nz``).
    A ``.json`` file holds an `ObjectIn` in its JSON form.
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix == ".npz":
        return _object_from_npz(path, **fields)
    if suffix == ".json":
        try:
            obj = ObjectIn.model_validate_json(path.read_bytes())
        except pydantic.ValidationError as exc:
            raise local_validation_error(exc, "object") from exc
        return as_object(obj, **fields)
    if suffix not in MESH_SUFFIXES:
        raise ValueError(f"{path}: unsupported file type {suffix!r}; use .npz, .json or one of {MESH_SUFFIXES}")
    trimesh = require("trimesh", "mesh", "a mesh as an object")

    loaded: Any = trimesh.load(str(path), process=suffix != ".ply")
    if isinstance(loaded, trimesh.Scene):
        loaded = loaded.to_geometry()
    if isinstance(loaded, trimesh.PointCloud) or len(getattr(loaded, "faces", ())) == 0:
        points = np.asarray(loaded.vertices)
        normals = _ply_normals(loaded)
        return object_from_points(points, normals, **fields)
    return object_from_mesh(loaded, num_points, seed=seed, **fields)


def _object_from_npz(path: Path, **fields: Any) -> ObjectIn:
    with np.load(path, allow_pickle=False) as data:
        arrays = {key: np.asarray(data[key]) for key in data.files}
    if "points" not in arrays:
        raise ValueError(f"{path}: no 'points' array (found: {', '.join(sorted(arrays)) or 'nothing'})")
    if "region_mask" in arrays and "region_mask" not in fields:
        fields["region_mask"] = arrays["region_mask"]
    if "vertices" in arrays and "faces" in arrays and "mesh" not in fields:
        fields["mesh"] = checked(MeshIn, "object.mesh", vertices=arrays["vertices"], faces=arrays["faces"])
    return object_from_points(arrays["points"], arrays.get("normals"), **fields)


def _ply_normals(cloud: Any) -> np.ndarray | None:
    """The ``nx, ny, nz`` vertex properties of a point-cloud ``.ply`` (trimesh keeps them in its raw data)."""
    raw = getattr(cloud, "metadata", {}).get("_ply_raw", {}).get("vertex", {}).get("data")
    if raw is None:
        return None
    names = set(raw) if isinstance(raw, dict) else set(getattr(raw.dtype, "names", None) or ())
    if not {"nx", "ny", "nz"} <= names:
        return None
    return np.stack([np.asarray(raw[k]).reshape(-1) for k in ("nx", "ny", "nz")], axis=-1).astype(np.float64)


def save_object(obj: ObjectIn, path: str | os.PathLike[str]) -> Path:
    """Write an object as ``.npz`` (points, normals, region_mask, vertices/faces) that `object_from_file` reads."""
    arrays: dict[str, np.ndarray] = {"points": obj.points}
    if obj.normals is not None:
        arrays["normals"] = obj.normals
    if obj.region_mask is not None:
        arrays["region_mask"] = obj.region_mask
    if obj.mesh is not None:
        arrays["vertices"], arrays["faces"] = obj.mesh.vertices, obj.mesh.faces
    path = Path(path)
    np.savez_compressed(path, **arrays)  # type: ignore[arg-type]
    return path


def as_object(value: ObjectLike, **fields: Any) -> ObjectIn:
    """Coerce an `ObjectIn`, array, trimesh mesh, file path or dict into an `ObjectIn`."""
    if isinstance(value, ObjectIn):
        return checked(ObjectIn, "object", **{**dict(value), **fields}) if fields else value
    if isinstance(value, dict):
        return checked(ObjectIn, "object", **{**value, **fields})
    if isinstance(value, str | os.PathLike):
        return object_from_file(value, **fields)
    if isinstance(value, np.ndarray | list | tuple):
        return object_from_points(value, **fields)
    if hasattr(value, "vertices") and hasattr(value, "faces"):
        return object_from_mesh(value, **fields)
    raise TypeError(f"cannot make an object from {type(value).__name__}; pass points, a mesh, a path or ObjectIn")
