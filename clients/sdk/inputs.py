"""Meet users where their data is: objects from arrays, meshes and files; tasks from poses and target clouds.

Everything returns the wire contract's models (`ObjectIn`, task models, `SynthesisRequest`), validated on the
spot, so a mistake is reported with the field's name before anything is sent. trimesh is imported only by the
functions that read meshes.
"""

from __future__ import annotations

import os
import re
from pathlib import Path
from typing import Any

import numpy as np
import pydantic

from clients.schemas import (
    ContactsIn,
    DeltaPoseTask,
    ForceClosureTask,
    MeshIn,
    ObjectIn,
    RobotIn,
    RobotRegister,
    SynthesisOptions,
    SynthesisRequest,
    TargetPointsTask,
    TaskIn,
    WrenchTask,
)
from clients.sdk.errors import local_validation_error

MESH_SUFFIXES = (".ply", ".obj", ".stl", ".off", ".glb")
DEFAULT_NUM_POINTS = 2048
# Meshes up to this many faces travel with the request (exact penetration checks); larger ones are left out.
MAX_MESH_FACES = 20_000

ObjectLike = ObjectIn | np.ndarray | str | os.PathLike[str] | dict[str, Any] | Any
TaskLike = TaskIn | str | dict[str, Any]
RobotLike = RobotIn | str | dict[str, Any]
_TASK_ADAPTER: pydantic.TypeAdapter[Any] = pydantic.TypeAdapter(TaskIn)


def _validated(cls: type[Any], what: str, **fields: Any) -> Any:
    try:
        return cls(**fields)
    except pydantic.ValidationError as exc:
        raise local_validation_error(exc, what) from exc


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
    return _validated(ObjectIn, "object", points=array, normals=normals, **fields)


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
    import trimesh

    if not isinstance(mesh, trimesh.Trimesh) or len(mesh.faces) == 0:
        raise TypeError(f"expected a trimesh.Trimesh with faces, got {type(mesh).__name__}")
    points, face_index = trimesh.sample.sample_surface(mesh, int(num_points), seed=seed)
    normals = np.asarray(mesh.face_normals)[face_index]
    if include_mesh is None:
        include_mesh = len(mesh.faces) <= MAX_MESH_FACES
    if include_mesh and "mesh" not in fields:
        fields["mesh"] = _validated(
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
    import trimesh

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
        fields["mesh"] = _validated(MeshIn, "object.mesh", vertices=arrays["vertices"], faces=arrays["faces"])
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
        return _validated(ObjectIn, "object", **{**dict(value), **fields}) if fields else value
    if isinstance(value, dict):
        return _validated(ObjectIn, "object", **{**value, **fields})
    if isinstance(value, str | os.PathLike):
        return object_from_file(value, **fields)
    if isinstance(value, np.ndarray | list | tuple):
        return object_from_points(value, **fields)
    if hasattr(value, "vertices") and hasattr(value, "faces"):
        return object_from_mesh(value, **fields)
    raise TypeError(f"cannot make an object from {type(value).__name__}; pass points, a mesh, a path or ObjectIn")


# ---- tasks ------------------------------------------------------------------------------------------------


def rotation_to_quaternion(rotation: Any) -> np.ndarray:
    """A unit quaternion (w, x, y, z) from a quaternion (4,), a rotation matrix (3, 3) or a transform (4, 4)."""
    r = np.asarray(rotation, dtype=np.float64)
    if r.shape == (4,):
        return r / np.linalg.norm(r)
    if r.shape == (4, 4):
        r = r[:3, :3]
    if r.shape != (3, 3):
        raise ValueError(f"rotation: expected (4,) quaternion, (3, 3) or (4, 4) matrix, got {r.shape}")
    # Shepperd's method: numerically stable for every rotation.
    trace = np.trace(r)
    candidates = [trace, r[0, 0], r[1, 1], r[2, 2]]
    k = int(np.argmax(candidates))
    if k == 0:
        s = 2.0 * np.sqrt(1.0 + trace)
        q = [0.25 * s, (r[2, 1] - r[1, 2]) / s, (r[0, 2] - r[2, 0]) / s, (r[1, 0] - r[0, 1]) / s]
    else:
        i, j, m = [(0, 1, 2), (1, 2, 0), (2, 0, 1)][k - 1]
        s = 2.0 * np.sqrt(1.0 + r[i, i] - r[j, j] - r[m, m])
        q = [0.0, 0.0, 0.0, 0.0]
        q[0] = (r[m, j] - r[j, m]) / s
        q[1 + i] = 0.25 * s
        q[1 + j] = (r[j, i] + r[i, j]) / s
        q[1 + m] = (r[m, i] + r[i, m]) / s
    out = np.asarray(q)
    return out / np.linalg.norm(out) * (1.0 if out[0] >= 0 else -1.0)


def delta_pose(translation: Any = (0.0, 0.0, 0.0), rotation: Any = None) -> DeltaPoseTask:
    """Move the object rigidly by ``translation`` (m) and ``rotation`` about its centre.

    Args:
        translation: (3,) metres; or a (4, 4) homogeneous transform (then ``rotation`` is taken from it).
        rotation: (4,) quaternion (w, x, y, z), or a (3, 3) rotation matrix; identity when None.
    """
    t = np.asarray(translation, dtype=np.float64)
    if t.shape == (4, 4):
        t, rotation = t[:3, 3], t[:3, :3] if rotation is None else rotation
    q = np.array([1.0, 0.0, 0.0, 0.0]) if rotation is None else rotation_to_quaternion(rotation)
    return _validated(DeltaPoseTask, "task", translation=t, rotation=q)


def target_points(targets: Any) -> TargetPointsTask:
    """Move each object point to its row of ``targets`` (N, 3), point-to-point with the object's points."""
    return _validated(TargetPointsTask, "task", targets=np.asarray(targets, dtype=np.float64))


def force_closure() -> ForceClosureTask:
    """Hold the object: a grasp that resists any wrench."""
    return ForceClosureTask()


def wrench(force: Any = (0.0, 0.0, 0.0), torque: Any = (0.0, 0.0, 0.0)) -> WrenchTask:
    """Apply ``force`` (N) and ``torque`` (N·m) about the object's centre of mass, world frame."""
    return _validated(WrenchTask, "task", wrench=np.concatenate([np.asarray(force), np.asarray(torque)]))


def as_task(value: TaskLike) -> TaskIn:
    """Coerce a task model, a dict with ``kind``, or the string ``"force_closure"`` into a task."""
    if isinstance(value, str):
        value = {"kind": value}
    if isinstance(value, dict):
        try:
            return _TASK_ADAPTER.validate_python(value)  # type: ignore[no-any-return]
        except pydantic.ValidationError as exc:
            raise local_validation_error(exc, "task") from exc
    return value


def as_robot(value: RobotLike) -> RobotIn:
    """Coerce a hand name (``"leap"``), a dict or a `RobotIn` into a `RobotIn`."""
    if isinstance(value, RobotIn):
        return value
    if isinstance(value, str):
        return _validated(RobotIn, "robot", name=value)
    return _validated(RobotIn, "robot", **value)


def make_request(
    object: ObjectLike | SynthesisRequest,
    task: TaskLike = "force_closure",
    robot: RobotLike = "leap",
    *,
    contacts: ContactsIn | dict[str, Any] | None = None,
    **options: Any,
) -> SynthesisRequest:
    """Build and validate a `SynthesisRequest`.

    Args:
        object: anything `as_object` takes: `ObjectIn`, (N, 3)/(N, 6) array, trimesh mesh, file path, dict.
        task: anything `as_task` takes (default: hold the object).
        robot: a hand name, `RobotIn` or dict (default ``"leap"``).
        contacts: given contacts (with ``method="contacts"`` or ``"auto"``).
        **options: `SynthesisOptions` fields: ``method``, ``num_proposals``, ``seed``, ``timeout``, ...

    A `SynthesisRequest` given as ``object`` is returned as it is (the other arguments are ignored).
    """
    if isinstance(object, SynthesisRequest):
        return object
    opts = _validated(SynthesisOptions, "options", **options)
    return _validated(
        SynthesisRequest,
        "request",
        object=as_object(object),
        task=as_task(task),
        robot=as_robot(robot),
        options=opts,
        contacts=contacts,
    )


def robot_registration(
    urdf: str | bytes | os.PathLike[str],
    fingertips: list[str],
    *,
    name: str | None = None,
    tip_offsets: Any = None,
) -> RobotRegister:
    """Build the body of ``POST /v1/robots`` from URDF text or a ``.urdf`` file.

    Args:
        urdf: the URDF XML (str or bytes) or a path to a ``.urdf`` file.
        fingertips: the fingertip link names, one per finger.
        name: the name to register under (default: the file's stem, else the URDF's ``<robot name>``),
            lower-cased with other characters than ``[a-z0-9_-]`` replaced by ``-``.
        tip_offsets: (len(fingertips), 3) offsets of the contact points in each fingertip link's frame, metres.
    """
    text: str
    if isinstance(urdf, bytes):
        text = urdf.decode("utf-8")
    elif isinstance(urdf, os.PathLike) or (isinstance(urdf, str) and not urdf.lstrip().startswith("<")):
        path = Path(urdf)
        if not path.is_file():
            raise FileNotFoundError(f"urdf: no file {str(path)[:80]!r}; pass URDF text (starting with '<') or a path")
        text = path.read_text(encoding="utf-8")
        name = name or path.stem
    else:
        text = urdf
    if name is None:
        match = re.search(r"<robot[^>]*\bname\s*=\s*[\"']([^\"']+)", text)
        name = match.group(1) if match else "custom-hand"
    clean = re.sub(r"[^a-z0-9_\-]", "-", name.lower()).strip("-_")[:64] or "custom-hand"
    offsets = None if tip_offsets is None else np.asarray(tip_offsets, dtype=np.float64)
    return _validated(RobotRegister, "robot", name=clean, urdf=text, fingertips=list(fingertips), tip_offsets=offsets)
