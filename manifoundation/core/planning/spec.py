"""Plan files for ``mani plan``: a YAML or JSON mapping with the wire schema's field names
(``manifoundation/contract/plans.py``), plus ``file`` entries that load an object or a mesh obstacle from disk (paths
relative to the plan file).

```yaml
object: {file: cup.npz, properties: {friction: 0.8}}     # or points / normals / mesh: {vertices, faces}
robot: {name: allegro}
start: {position: [0.3, 0, 0.0]}                         # quaternion (w, x, y, z) defaults to the identity
waypoints: [{position: [0.3, 0, 0.2]}, {position: [-0.2, 0.1, 0.2], quaternion: [0.92, 0, 0, 0.38]}]
scene:
  support_plane: {height: 0.0}
  obstacles:
    - {kind: box, name: shelf, size: [0.3, 0.02, 0.3], pose: {position: [0, 0.2, 0.15]}}
    - {kind: mesh, name: bowl, file: bowl.stl, pose: {position: [0.2, -0.2, 0]}}
    - {kind: points, name: scan, file: scan.npz, resolution: 0.01}
options: {time_limit: 5, translation_step: 0.02, rotation_step: 0.2, seed: 0, method: random_contacts}
```

Loading checks field names and types and reports the first problem as `InvalidPlan` naming it; ranges and
shapes are then checked by `manifoundation.core.planning.validate`.
"""

from __future__ import annotations

import dataclasses
import json
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import numpy as np

from manifoundation.core.planning.obstacles import BoxObstacle, MeshObstacle, Obstacle, PointCloudObstacle, SupportPlane
from manifoundation.core.planning.poses import Pose
from manifoundation.core.planning.types import InvalidPlan, PlanInput, PlanOptions
from manifoundation.core.robots.hand import Hand

DEFAULT_NUM_POINTS = 1024
MESH_SUFFIXES = (".obj", ".stl", ".ply", ".off", ".glb", ".gltf", ".dae")


def _mapping(name: str, value: Any, allowed: set[str], required: frozenset[str] | set[str] = frozenset()
             ) -> Mapping[str, Any]:  # fmt: skip
    if not isinstance(value, Mapping):
        raise InvalidPlan(f"{name}: expected a mapping, got {type(value).__name__}")
    unknown = sorted(set(value) - allowed)
    if unknown:
        raise InvalidPlan(f"{name}: unknown field(s) {', '.join(unknown)} (allowed: {', '.join(sorted(allowed))})")
    missing = sorted(required - set(value))
    if missing:
        raise InvalidPlan(f"{name}: missing field(s) {', '.join(missing)}")
    return value


def _numbers(name: str, value: Any) -> np.ndarray:
    try:
        return np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise InvalidPlan(f"{name}: expected numbers ({exc})") from exc


def pose_from(name: str, value: Any) -> Pose:
    """A pose from ``{position: [x, y, z], quaternion: [w, x, y, z]}`` (quaternion optional)."""
    data = _mapping(name, value, {"position", "quaternion"}, {"position"})
    quat = _numbers(f"{name}.quaternion", data.get("quaternion", [1.0, 0.0, 0.0, 0.0]))
    if quat.shape == (4,) and np.linalg.norm(quat) > 1e-9:
        quat = quat / np.linalg.norm(quat)  # as the wire schema does
    return Pose(_numbers(f"{name}.position", data["position"]), quat)


def _load_arrays(name: str, path: Path) -> dict[str, np.ndarray]:
    if not path.is_file():
        raise InvalidPlan(f"{name}.file: {path} not found")
    if path.suffix.lower() == ".npz":
        with np.load(path, allow_pickle=False) as z:
            return {k: np.asarray(z[k]) for k in z.files}
    if path.suffix.lower() not in MESH_SUFFIXES:
        raise InvalidPlan(f"{name}.file: unsupported type {path.suffix!r} (.npz or {', '.join(MESH_SUFFIXES)})")
    import trimesh

    loaded: Any = trimesh.load(str(path))
    if isinstance(loaded, trimesh.Scene):
        loaded = loaded.to_geometry()
    out = {"vertices": np.asarray(loaded.vertices, dtype=np.float64)}
    if len(getattr(loaded, "faces", ())):
        out["faces"] = np.asarray(loaded.faces, dtype=np.int64)
    return out


def _object(value: Any, base: Path) -> dict[str, Any]:
    data = _mapping("object", value, {"file", "points", "normals", "mesh", "properties", "region_mask", "num_points"})
    arrays: dict[str, Any] = {}
    if "file" in data:
        loaded = _load_arrays("object", base / str(data["file"]))
        if "points" not in loaded and "faces" in loaded:  # a mesh file: sample its surface
            import trimesh

            surface = trimesh.Trimesh(loaded["vertices"], loaded["faces"])
            count = int(data.get("num_points", DEFAULT_NUM_POINTS))
            pts, faces = trimesh.sample.sample_surface(surface, count, seed=0)
            loaded = {**loaded, "points": np.asarray(pts), "normals": np.asarray(surface.face_normals[faces])}
        arrays.update(loaded)
    for key in ("points", "normals", "region_mask"):
        if key in data:
            arrays[key] = data[key]
    if "mesh" in data:
        mesh = _mapping("object.mesh", data["mesh"], {"vertices", "faces"}, {"vertices", "faces"})
        arrays["vertices"], arrays["faces"] = mesh["vertices"], mesh["faces"]
    if "points" not in arrays:
        raise InvalidPlan("object: give points (or a file with them, or a mesh file)")
    props = _mapping("object.properties", data.get("properties", {}), {"friction", "density"})
    mask = arrays.get("region_mask")
    return {
        "points": _numbers("object.points", arrays["points"]),
        "normals": None if arrays.get("normals") is None else _numbers("object.normals", arrays["normals"]),
        "mesh_vertices": None if "vertices" not in arrays else _numbers("object.mesh.vertices", arrays["vertices"]),
        "mesh_faces": None if "faces" not in arrays else np.asarray(arrays["faces"], dtype=np.int64),
        "properties": {k: float(v) for k, v in props.items()},
        "mask": None if mask is None else np.asarray(mask).astype(bool),
    }


def _obstacle(name: str, value: Any, base: Path) -> Obstacle:
    kind = value.get("kind") if isinstance(value, Mapping) else None
    if kind == "box":
        data = _mapping(name, value, {"kind", "name", "size", "pose"}, {"size"})
        pose = pose_from(f"{name}.pose", data["pose"]) if "pose" in data else Pose()
        return BoxObstacle(_numbers(f"{name}.size", data["size"]), pose, str(data.get("name", "")))
    if kind == "mesh":
        data = _mapping(name, value, {"kind", "name", "file", "vertices", "faces", "pose"})
        arrays = _load_arrays(name, base / str(data["file"])) if "file" in data else dict(data)
        if "vertices" not in arrays or "faces" not in arrays:
            raise InvalidPlan(f"{name}: a mesh obstacle needs vertices and faces (or a mesh file)")
        pose = pose_from(f"{name}.pose", data["pose"]) if "pose" in data else Pose()
        return MeshObstacle(_numbers(f"{name}.vertices", arrays["vertices"]), np.asarray(arrays["faces"], np.int64),
                            pose, str(data.get("name", "")))  # fmt: skip
    if kind == "points":
        data = _mapping(name, value, {"kind", "name", "file", "points", "resolution"})
        arrays = _load_arrays(name, base / str(data["file"])) if "file" in data else dict(data)
        points = arrays.get("points", arrays.get("vertices"))
        if points is None:
            raise InvalidPlan(f"{name}: a point-cloud obstacle needs points (or a file with them)")
        return PointCloudObstacle(_numbers(f"{name}.points", points), float(data.get("resolution", 0.01)),
                                  str(data.get("name", "")))  # fmt: skip
    raise InvalidPlan(f"{name}.kind: {kind!r} is not one of box, mesh, points")


def _options(value: Any) -> PlanOptions:
    names = {f.name for f in dataclasses.fields(PlanOptions)} - {"deadline"}
    data = _mapping("options", value, names)
    defaults = PlanOptions()
    out: dict[str, Any] = {}
    for key, raw in data.items():
        want = type(getattr(defaults, key))
        if want is bool and not isinstance(raw, bool):
            raise InvalidPlan(f"options.{key}: expected true or false")
        try:
            out[key] = want(raw)
        except (TypeError, ValueError) as exc:
            raise InvalidPlan(f"options.{key}: expected {want.__name__} ({exc})") from exc
    return PlanOptions(**out)


def plan_from_dict(data: Any, base: Path, get_hand: Callable[[str], Hand]) -> PlanInput:
    """A `PlanInput` from a plan mapping (see module doc); ``get_hand`` resolves ``robot.name``.

    Raises:
        InvalidPlan: a wrong field name or type, a missing field, an unknown hand, an unreadable file.
    """
    top = _mapping("plan", data, {"object", "robot", "start", "waypoints", "scene", "options"},
                   {"object", "robot", "start", "waypoints"})  # fmt: skip
    robot = _mapping("robot", top["robot"], {"name"}, {"name"})
    try:
        hand = get_hand(str(robot["name"]))
    except LookupError as exc:  # `manifoundation.core.robots.UnknownHand`
        raise InvalidPlan(f"robot.name: {exc.args[0] if exc.args else robot['name']}") from exc
    waypoints = top["waypoints"]
    if not isinstance(waypoints, list):
        raise InvalidPlan("waypoints: expected a list of poses")
    scene = _mapping("scene", top.get("scene", {}), {"obstacles", "support_plane"})
    obstacles = scene.get("obstacles", [])
    if not isinstance(obstacles, list):
        raise InvalidPlan("scene.obstacles: expected a list")
    support = None
    if scene.get("support_plane") is not None:
        plane = _mapping("scene.support_plane", scene["support_plane"], {"height", "tolerance"})
        support = SupportPlane(float(plane.get("height", 0.0)), float(plane.get("tolerance", 1e-3)))
    return PlanInput(
        hand=hand,
        start=pose_from("start", top["start"]),
        waypoints=[pose_from(f"waypoints[{i}]", w) for i, w in enumerate(waypoints)],
        obstacles=[_obstacle(f"scene.obstacles[{i}]", o, base) for i, o in enumerate(obstacles)],
        support=support,
        options=_options(top.get("options", {})),
        hand_key=str(robot["name"]),
        **_object(top["object"], base),
    )


def load_plan_file(path: Path, get_hand: Callable[[str], Hand]) -> PlanInput:
    """Read a ``.yaml`` / ``.yml`` / ``.json`` plan file (see module doc)."""
    text = path.read_text()
    if path.suffix.lower() in (".yaml", ".yml"):
        import yaml

        data = yaml.safe_load(text)
    else:
        try:
            data = json.loads(text)
        except json.JSONDecodeError as exc:
            raise InvalidPlan(f"plan: {path} is not valid JSON ({exc})") from exc
    return plan_from_dict(data, path.parent, get_hand)
