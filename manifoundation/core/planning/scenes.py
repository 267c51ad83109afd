"""Scenes and objects for the example, the benchmark and the tests: a cup, an open box, a cluttered table.

All in metres, z up, the table top at z = 0.
"""

from __future__ import annotations

import numpy as np
import trimesh

from manifoundation.core.planning.obstacles import BoxObstacle, SupportPlane
from manifoundation.core.planning.poses import Pose


def cup_mesh(radius: float = 0.035, height: float = 0.09, wall: float = 0.004, base: float = 0.006) -> trimesh.Trimesh:
    """A watertight cup (a revolved profile: wall and base), its frame at the centre of its bottom, z up."""
    inner = radius - wall
    profile = np.array([[0, 0], [radius, 0], [radius, height], [inner, height], [inner, base], [0, base]])
    return trimesh.creation.revolve(profile, sections=48)


def sampled(mesh: trimesh.Trimesh, count: int = 1024, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """(count, 3) area-uniform surface points of ``mesh`` and their outward face normals (count, 3)."""
    points, faces = trimesh.sample.sample_surface(mesh, count, seed=seed)
    return np.asarray(points, dtype=np.float64), np.asarray(mesh.face_normals[faces], dtype=np.float64)


def open_box(centre: np.ndarray, inner: np.ndarray, wall: float = 0.01, name: str = "box") -> list[BoxObstacle]:
    """An open-topped box standing on the table: a floor and four walls around an ``inner`` (3,) space whose
    footprint is centred on ``centre`` (2,) or (3,) (x, y used)."""
    cx, cy = float(centre[0]), float(centre[1])
    ix, iy, iz = (float(v) for v in inner)
    floor = BoxObstacle(np.array([ix + 2 * wall, iy + 2 * wall, wall]), Pose(np.array([cx, cy, wall / 2])),
                        f"{name}_floor")  # fmt: skip
    z = wall + iz / 2
    x_size, y_size = np.array([wall, iy + 2 * wall, iz]), np.array([ix, wall, iz])
    walls = [BoxObstacle(x_size, Pose(np.array([cx + s * (ix + wall) / 2, cy, z])), f"{name}_wall_{n}x")
             for s, n in ((1, "p"), (-1, "n"))]  # fmt: skip
    walls += [BoxObstacle(y_size, Pose(np.array([cx, cy + s * (iy + wall) / 2, z])), f"{name}_wall_{n}y")
              for s, n in ((1, "p"), (-1, "n"))]  # fmt: skip
    return [floor, *walls]


def cluttered_table(count: int, seed: int, extent: float = 0.5, keep_clear: list[np.ndarray] | None = None,
                    clear_radius: float = 0.12) -> tuple[list[BoxObstacle], SupportPlane]:  # fmt: skip
    """``count`` seeded boxes (4-12 cm wide, 5-30 cm tall, turned about z) standing on a table within
    ±``extent`` m, none within ``clear_radius`` (horizontally) of the ``keep_clear`` points; and the table."""
    rng = np.random.default_rng(seed)
    clear = [np.asarray(p, dtype=np.float64)[:2] for p in (keep_clear or [])]
    boxes: list[BoxObstacle] = []
    tries = 0
    while len(boxes) < count and tries < 100 * count:
        tries += 1
        xy = rng.uniform(-extent, extent, size=2)
        size = np.array([*rng.uniform(0.04, 0.12, size=2), rng.uniform(0.05, 0.30)])
        if any(np.linalg.norm(xy - c) < clear_radius + 0.5 * np.linalg.norm(size[:2]) for c in clear):
            continue
        yaw = rng.uniform(0, np.pi)
        quat = np.array([np.cos(yaw / 2), 0.0, 0.0, np.sin(yaw / 2)])
        boxes.append(BoxObstacle(size, Pose(np.array([xy[0], xy[1], size[2] / 2]), quat), f"clutter{len(boxes)}"))
    return boxes, SupportPlane(0.0)
