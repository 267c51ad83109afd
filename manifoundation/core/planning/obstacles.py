"""The scene's obstacles (world frame, metres) and their python-fcl collision geometry.

- a box: an fcl ``Box`` primitive (solid: a body inside it collides);
- a mesh: an fcl BVH of its triangles. A BVH is a surface, so a body entirely inside a closed mesh meets no
  triangle; poses the planner does not reach by a checked motion (start, waypoints, repairs) are therefore also
  tested for containment (`MeshObstacle.contains`: trimesh's ray-cast inside test of a watertight mesh);
- a point cloud (e.g. from a depth camera): the voxels of side ``resolution`` that hold a point, each a solid fcl
  ``Box`` — the occupied space, not a hull (a hull would fill a bowl's inside);
- a support plane (a table, z up): not an fcl object; a body is above it when its lowest vertex is, which is
  exact for meshes. It may rest on it: ``tolerance`` below the plane is allowed.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import cast

import fcl
import numpy as np
import trimesh

from manifoundation.core.planning.poses import IDENTITY, Pose, quaternion_matrix

MAX_VOXELS = 20_000


@dataclass
class BoxObstacle:
    """A box of full extents ``size`` (3,) m centred on ``pose``."""

    size: np.ndarray
    pose: Pose = IDENTITY
    name: str = ""

    def collision_objects(self) -> list[fcl.CollisionObject]:
        """One solid fcl box."""
        sx, sy, sz = (float(s) for s in self.size)
        return [fcl.CollisionObject(fcl.Box(sx, sy, sz), _transform(self.pose))]

    def mesh(self) -> trimesh.Trimesh:
        """The box as a world-frame mesh (views, containment)."""
        box: trimesh.Trimesh = trimesh.creation.box(
            extents=np.asarray(self.size, dtype=np.float64), transform=self.pose.matrix()
        )
        return box


@dataclass
class MeshObstacle:
    """A triangle mesh: ``vertices`` (V, 3) and ``faces`` (F, 3) in the obstacle's frame, placed by ``pose``."""

    vertices: np.ndarray
    faces: np.ndarray
    pose: Pose = IDENTITY
    name: str = ""
    _world: trimesh.Trimesh | None = field(default=None, init=False, repr=False, compare=False)

    def collision_objects(self) -> list[fcl.CollisionObject]:
        """One fcl BVH of the triangles."""
        return [fcl.CollisionObject(bvh(np.asarray(self.vertices), np.asarray(self.faces)), _transform(self.pose))]

    def mesh(self) -> trimesh.Trimesh:
        """The mesh in the world frame."""
        if self._world is None:
            self._world = trimesh.Trimesh(self.pose.apply(self.vertices), np.asarray(self.faces), process=False)
        return self._world

    def contains(self, points: np.ndarray) -> np.ndarray:
        """(M,) whether each point (M, 3) is inside the mesh (False for all when it is not watertight)."""
        mesh = self.mesh()
        if not mesh.is_watertight:
            return np.zeros(len(points), dtype=bool)
        return np.asarray(mesh.contains(np.asarray(points, dtype=np.float64)), dtype=bool)


@dataclass
class PointCloudObstacle:
    """Points (P, 3) sensed on obstacles, world frame; occupied voxels of side ``resolution`` (m) collide."""

    points: np.ndarray
    resolution: float = 0.01
    name: str = ""

    def voxel_centres(self) -> np.ndarray:
        """(K, 3) centres of the occupied voxels."""
        cells = np.unique(np.floor(np.asarray(self.points, dtype=np.float64) / self.resolution).astype(np.int64),
                          axis=0)  # fmt: skip
        if len(cells) > MAX_VOXELS:
            raise ValueError(f"{len(cells)} occupied voxels at resolution {self.resolution} m (at most {MAX_VOXELS})")
        return (cells + 0.5) * self.resolution

    def collision_objects(self) -> list[fcl.CollisionObject]:
        """One solid fcl box per occupied voxel."""
        r = float(self.resolution)
        return [fcl.CollisionObject(fcl.Box(r, r, r), fcl.Transform(np.eye(3), c)) for c in self.voxel_centres()]

    def mesh(self) -> trimesh.Trimesh:
        """The occupied voxels as one world-frame mesh (views)."""
        boxes = [trimesh.creation.box(extents=[self.resolution] * 3, transform=_translation(c))
                 for c in self.voxel_centres()]  # fmt: skip
        return cast(trimesh.Trimesh, trimesh.util.concatenate(boxes))


Obstacle = BoxObstacle | MeshObstacle | PointCloudObstacle


@dataclass
class SupportPlane:
    """The plane z = ``height`` (a table), free space above; bodies may reach ``tolerance`` (m) below it."""

    height: float = 0.0
    tolerance: float = 1e-3

    def clearance(self, vertices: np.ndarray) -> float:
        """How far (m) the lowest of the world vertices (M, 3) is above the plane (negative: below)."""
        return float(np.min(vertices[:, 2])) - self.height if len(vertices) else np.inf

    def supports(self, vertices: np.ndarray) -> bool:
        """Whether the body with these world vertices (M, 3) is not below the plane beyond the tolerance."""
        return self.clearance(vertices) >= -self.tolerance


def bvh(vertices: np.ndarray, faces: np.ndarray) -> fcl.BVHModel:
    """An fcl BVH of a triangle mesh (V, 3), (F, 3)."""
    model = fcl.BVHModel()
    model.beginModel(len(vertices), len(faces))
    model.addSubModel(np.asarray(vertices, dtype=np.float64), np.asarray(faces, dtype=np.int32))
    model.endModel()
    return model


def _transform(pose: Pose) -> fcl.Transform:
    return fcl.Transform(quaternion_matrix(pose.quaternion), np.asarray(pose.position, dtype=np.float64))


def _translation(centre: np.ndarray) -> np.ndarray:
    m = np.eye(4)
    m[:3, 3] = centre
    return m


def obstacle_names(obstacles: list[Obstacle]) -> list[str]:
    """Each obstacle's name, ``scene.obstacles[i]`` for those without one (names are what errors and answers cite)."""
    return [o.name or f"scene.obstacles[{i}]" for i, o in enumerate(obstacles)]
