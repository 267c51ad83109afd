"""Checks of a `PlanInput` before any planning: every problem is an `InvalidPlan` naming its field."""

from __future__ import annotations

import numpy as np

from manifoundation.core.pipeline.types import MAX_PROPOSALS
from manifoundation.core.planning.obstacles import BoxObstacle, MeshObstacle, PointCloudObstacle
from manifoundation.core.planning.poses import Pose
from manifoundation.core.planning.types import REPAIR_MODES, InvalidPlan, PlanInput, PlanOptions

MAX_WAYPOINTS = 64
MAX_OBSTACLES = 64
PLAN_METHODS = ("network", "random_contacts")


def _array(name: str, value: object, shape: tuple[int | None, ...]) -> np.ndarray:
    arr = np.asarray(value, dtype=np.float64)
    if arr.ndim != len(shape) or any(s is not None and s != a for s, a in zip(shape, arr.shape, strict=True)):
        want = tuple("N" if s is None else s for s in shape)
        raise InvalidPlan(f"{name}: expected shape {want}, got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise InvalidPlan(f"{name}: contains NaN or inf")
    return arr


def check_pose(name: str, pose: Pose) -> None:
    """A finite position (3,) and a unit quaternion (4,)."""
    _array(f"{name}.position", pose.position, (3,))
    quat = _array(f"{name}.quaternion", pose.quaternion, (4,))
    if abs(float(np.linalg.norm(quat)) - 1.0) > 1e-6:
        raise InvalidPlan(f"{name}.quaternion: not a unit quaternion (norm {np.linalg.norm(quat):.6f})")


def _positive(name: str, value: float, upper: float = np.inf) -> None:
    if not (np.isfinite(value) and 0 < value <= upper):
        raise InvalidPlan(f"{name}: {value} is outside (0, {upper}]")


def check_options(opt: PlanOptions) -> None:
    """Ranges of the options (see `PlanOptions`)."""
    _positive("options.time_limit", opt.time_limit, 600.0)
    _positive("options.translation_step", opt.translation_step, 1.0)
    _positive("options.rotation_step", opt.rotation_step, np.pi)
    _positive("options.max_repair_distance", opt.max_repair_distance, 2.0)
    _positive("options.collision_resolution", opt.collision_resolution, 0.1)
    _positive("options.workspace_margin", opt.workspace_margin, 10.0)
    _positive("options.max_contact_shift", opt.max_contact_shift, 1.0)
    if opt.repair not in REPAIR_MODES:
        raise InvalidPlan(f"options.repair: {opt.repair!r} is not one of {', '.join(REPAIR_MODES)}")
    if opt.method not in PLAN_METHODS:
        raise InvalidPlan(f"options.method: {opt.method!r} is not one of {', '.join(PLAN_METHODS)}")
    if not 1 <= opt.num_proposals <= MAX_PROPOSALS:
        raise InvalidPlan(f"options.num_proposals: {opt.num_proposals} is outside 1..{MAX_PROPOSALS}")
    if not 1 <= opt.max_iterations <= 500:
        raise InvalidPlan(f"options.max_iterations: {opt.max_iterations} is outside 1..500")
    if not 1 <= opt.new_grasp_attempts <= 8:
        raise InvalidPlan(f"options.new_grasp_attempts: {opt.new_grasp_attempts} is outside 1..8")
    if opt.lookahead < 0 or opt.seed < 0:
        raise InvalidPlan("options.lookahead and options.seed must be ≥ 0")


def _check_obstacles(inp: PlanInput) -> None:
    if len(inp.obstacles) > MAX_OBSTACLES:
        raise InvalidPlan(f"scene.obstacles: {len(inp.obstacles)} given, at most {MAX_OBSTACLES}")
    for i, obs in enumerate(inp.obstacles):
        name = f"scene.obstacles[{i}]"
        if isinstance(obs, BoxObstacle):
            size = _array(f"{name}.size", obs.size, (3,))
            if np.any(size <= 0):
                raise InvalidPlan(f"{name}.size: every extent must be > 0")
            check_pose(f"{name}.pose", obs.pose)
        elif isinstance(obs, MeshObstacle):
            verts = _array(f"{name}.vertices", obs.vertices, (None, 3))
            faces = np.asarray(obs.faces)
            if faces.ndim != 2 or faces.shape[1] != 3 or len(faces) == 0:
                raise InvalidPlan(f"{name}.faces: expected shape (F, 3) with F ≥ 1, got {faces.shape}")
            if faces.min() < 0 or faces.max() >= len(verts):
                raise InvalidPlan(f"{name}.faces: index vertices outside 0..{len(verts) - 1}")
            check_pose(f"{name}.pose", obs.pose)
        elif isinstance(obs, PointCloudObstacle):
            pts = _array(f"{name}.points", obs.points, (None, 3))
            if len(pts) == 0:
                raise InvalidPlan(f"{name}.points: empty")
            _positive(f"{name}.resolution", obs.resolution, 0.5)
            try:
                obs.voxel_centres()
            except ValueError as exc:
                raise InvalidPlan(f"{name}: {exc}") from exc
        else:
            raise InvalidPlan(f"{name}: unknown obstacle type {type(obs).__name__}")
    if inp.support is not None and not (np.isfinite(inp.support.height) and 0 <= inp.support.tolerance <= 0.05):
        raise InvalidPlan("scene.support_plane: height must be finite and tolerance within [0, 0.05] m")


def check_plan(inp: PlanInput) -> None:
    """Validate the request's shapes, poses, scene and options (the object's own arrays are checked again by
    the synthesis pipeline at every step).

    Raises:
        InvalidPlan: the first problem found, naming its field.
    """
    points = _array("points", inp.points, (None, 3))
    if len(points) < 16:
        raise InvalidPlan(f"points: {len(points)} points, need at least 16")
    if inp.normals is not None:
        _array("normals", inp.normals, (len(points), 3))
    if (inp.mesh_vertices is None) != (inp.mesh_faces is None):
        raise InvalidPlan("mesh: give both vertices and faces, or neither")
    if inp.mesh_vertices is not None:
        verts = _array("mesh.vertices", inp.mesh_vertices, (None, 3))
        faces = np.asarray(inp.mesh_faces)
        if faces.ndim != 2 or faces.shape[1] != 3 or faces.min() < 0 or faces.max() >= len(verts):
            raise InvalidPlan("mesh.faces: expected (F, 3) indices into mesh.vertices")
    check_pose("start", inp.start)
    if not 1 <= len(inp.waypoints) <= MAX_WAYPOINTS:
        raise InvalidPlan(f"waypoints: {len(inp.waypoints)} given, need 1..{MAX_WAYPOINTS}")
    for i, w in enumerate(inp.waypoints):
        check_pose(f"waypoints[{i}]", w)
    _check_obstacles(inp)
    check_options(inp.options)
