"""What the viewer draws of a plan's scene: its obstacles as world-frame meshes or points, bounded in size.

The planner's own collision geometry lives in the worker (python-fcl); the API process keeps only this drawing
of the request's scene (numpy, no science): a box's 8 corners and 12 triangles placed by its pose, a mesh's
triangles placed by its pose (at most ``MAX_VIEW_FACES`` faces, else its vertices as points), a point cloud's
points (at most ``MAX_VIEW_POINTS``, evenly subsampled).
"""

from __future__ import annotations

import numpy as np

from manifoundation.contract import BoxObstacleIn, MeshObstacleIn, ObstacleIn, PlanRequest, PoseIn, SceneObstacle

MAX_VIEW_FACES = 20_000
MAX_VIEW_POINTS = 4096
_BOX_FACES = [
    [0, 2, 1], [1, 2, 3], [4, 5, 6], [5, 7, 6], [0, 1, 4], [1, 5, 4],
    [2, 6, 3], [3, 6, 7], [0, 4, 2], [2, 4, 6], [1, 3, 5], [3, 7, 5],
]  # fmt: skip
"""The triangles of the corners ordered by (x, y, z) sign bits (x slowest)."""


def quaternion_matrix(q: np.ndarray) -> np.ndarray:
    """The (3, 3) rotation of a unit quaternion (4,) (w, x, y, z)."""
    w, x, y, z = (float(v) for v in q)
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])


def placed(pose: PoseIn, points: np.ndarray) -> np.ndarray:
    """``points`` (N, 3) of a body placed in the world by ``pose``: R p + t."""
    return np.asarray(points, dtype=np.float64) @ quaternion_matrix(pose.quaternion).T + pose.position


def evenly(rows: np.ndarray, limit: int = MAX_VIEW_POINTS) -> np.ndarray:
    """At most ``limit`` of ``rows``, evenly spaced (all of them when there are no more)."""
    if len(rows) <= limit:
        return rows
    return rows[np.linspace(0, len(rows) - 1, limit).astype(np.int64)]


def _rounded(rows: np.ndarray) -> list[list[float]]:
    return np.asarray(rows, dtype=np.float64).round(5).tolist()


def obstacle_view(obstacle: ObstacleIn, index: int) -> SceneObstacle:
    """One obstacle as drawn (unnamed ones are named as the planner cites them: ``scene.obstacles[i]``)."""
    name = obstacle.name or f"scene.obstacles[{index}]"
    if isinstance(obstacle, BoxObstacleIn):
        signs = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)], dtype=np.float64)
        corners = placed(obstacle.pose, signs * np.asarray(obstacle.size) / 2)
        return SceneObstacle(name=name, kind="box", vertices=_rounded(corners), faces=_BOX_FACES)
    if isinstance(obstacle, MeshObstacleIn):
        vertices = placed(obstacle.pose, obstacle.vertices)
        if len(obstacle.faces) <= MAX_VIEW_FACES:
            return SceneObstacle(name=name, kind="mesh", vertices=_rounded(vertices),
                                 faces=np.asarray(obstacle.faces, dtype=np.int64).tolist())  # fmt: skip
        return SceneObstacle(name=name, kind="points", vertices=_rounded(evenly(vertices, MAX_VIEW_POINTS)))
    return SceneObstacle(name=name, kind="points", vertices=_rounded(evenly(obstacle.points, MAX_VIEW_POINTS)))


def scene_view(request: PlanRequest) -> tuple[list[SceneObstacle], float | None, list[list[float]]]:
    """The request's obstacles as drawn, its support plane's height (None: none) and its waypoints' positions."""
    scene = request.scene
    obstacles = [obstacle_view(o, i) for i, o in enumerate(scene.obstacles)]
    height = None if scene.support_plane is None else float(scene.support_plane.height)
    return obstacles, height, [np.asarray(w.position, dtype=np.float64).tolist() for w in request.waypoints]
