"""The collision world of a plan: the scene's obstacles and the two bodies that move through it — the object and
the hand that carries it — as python-fcl collision objects.

The object collides by its mesh when the request has one, else by its points' convex hull (a conservative cover:
a path the hull can take, the object can take). The hand collides by its links' collision meshes
(`manifoundation.core.robots.Hand.collision_meshes`) posed by its forward kinematics. Every query answers either fast (a
bool, for the planner's many calls: one fcl broad phase over the whole scene) or with the names of what was hit.
"""

from __future__ import annotations

from dataclasses import dataclass

import fcl
import numpy as np
import torch
import trimesh

from manifoundation.core.planning.obstacles import MeshObstacle, Obstacle, SupportPlane, bvh, obstacle_names
from manifoundation.core.planning.poses import Pose, quaternion_matrix
from manifoundation.core.robots.hand import Hand

PLANE = "support_plane"


@dataclass
class _HandBodies:
    names: list[str]
    objects: list[fcl.CollisionObject]
    vertices: list[np.ndarray]  # per body, body frame (k, 3)
    manager: fcl.DynamicAABBTreeCollisionManager


def _manager(objects: list[fcl.CollisionObject]) -> fcl.DynamicAABBTreeCollisionManager:
    manager = fcl.DynamicAABBTreeCollisionManager()
    manager.registerObjects(objects)
    manager.setup()
    return manager


def _hit(manager: fcl.DynamicAABBTreeCollisionManager, other: object) -> bool:
    data = fcl.CollisionData(request=fcl.CollisionRequest())
    manager.collide(other, data, fcl.defaultCollisionCallback)
    return bool(data.result.is_collision)


class CollisionScene:
    """Obstacles + support plane, and collision queries for the object at a pose and the hand at a pose.

    Args:
        obstacles: the scene (world frame).
        support: the support plane, or None.
        object_vertices, object_faces: the object's collision mesh, body frame (V, 3), (F, 3).
    """

    def __init__(
        self, obstacles: list[Obstacle], support: SupportPlane | None, object_vertices: np.ndarray,
        object_faces: np.ndarray,
    ) -> None:  # fmt: skip
        self.obstacles = obstacles
        self.support = support
        self.names = obstacle_names(obstacles)
        self._parts = [o.collision_objects() for o in obstacles]
        self._managers = [_manager(p) for p in self._parts]
        everything = [obj for part in self._parts for obj in part]
        self._all = _manager(everything) if everything else None
        self.object_vertices = np.asarray(object_vertices, dtype=np.float64)
        self.object_faces = np.asarray(object_faces, dtype=np.int64)
        self._object = fcl.CollisionObject(bvh(self.object_vertices, self.object_faces), fcl.Transform())
        self._hands: dict[int, _HandBodies] = {}

    @classmethod
    def for_object(
        cls, obstacles: list[Obstacle], support: SupportPlane | None, points: np.ndarray,
        mesh_vertices: np.ndarray | None = None, mesh_faces: np.ndarray | None = None,
    ) -> CollisionScene:  # fmt: skip
        """The scene with the object's mesh, or its points' convex hull when it has none."""
        if mesh_vertices is not None and mesh_faces is not None:
            return cls(obstacles, support, mesh_vertices, mesh_faces)
        hull = trimesh.convex.convex_hull(np.asarray(points, dtype=np.float64))
        return cls(obstacles, support, np.asarray(hull.vertices), np.asarray(hull.faces))

    @property
    def object_radius(self) -> float:
        """The largest distance (m) from the object frame's origin to its collision mesh."""
        return float(np.linalg.norm(self.object_vertices, axis=1).max())

    # ------------------------------------------------------------------ the object
    def _place_object(self, pose: Pose) -> None:
        self._object.setTransform(fcl.Transform(quaternion_matrix(pose.quaternion), np.asarray(pose.position, float)))

    def object_free(self, pose: Pose) -> bool:
        """Whether the object at ``pose`` is clear of every obstacle and above the support plane (fast)."""
        if self.support is not None and not self.support.supports(pose.apply(self.object_vertices)):
            return False
        if self._all is None:
            return True
        self._place_object(pose)
        return not _hit(self._all, self._object)

    def object_hits(self, pose: Pose, containment: bool = True) -> list[str]:
        """Names of what the object at ``pose`` meets: obstacles (with ``containment``, also a closed mesh
        obstacle that holds the object's centre) and ``"support_plane"``."""
        hits = []
        if self.support is not None and not self.support.supports(pose.apply(self.object_vertices)):
            hits.append(PLANE)
        self._place_object(pose)
        centre = pose.apply(self.object_vertices.mean(axis=0)[None])
        for name, manager, obstacle in zip(self.names, self._managers, self.obstacles, strict=True):
            inside = containment and isinstance(obstacle, MeshObstacle) and bool(obstacle.contains(centre)[0])
            if inside or _hit(manager, self._object):
                hits.append(name)
        return hits

    # ------------------------------------------------------------------ the hand
    def _hand(self, hand: Hand) -> _HandBodies:
        key = id(hand)
        if key not in self._hands:
            names, objects, vertices = [], [], []
            for name, mesh in hand.collision_meshes.items():
                if len(mesh.faces) == 0:
                    continue
                names.append(name)
                objects.append(fcl.CollisionObject(bvh(np.asarray(mesh.vertices), np.asarray(mesh.faces))))
                vertices.append(np.asarray(mesh.vertices, dtype=np.float64))
            self._hands[key] = _HandBodies(names, objects, vertices, _manager(objects))
        return self._hands[key]

    def hand_hits(self, hand: Hand, palm: Pose, q: np.ndarray) -> list[str]:
        """Names of the obstacles (and ``"support_plane"``) that the hand's collision meshes meet with the palm
        at ``palm`` and finger joints ``q`` (D,)."""
        bodies = self._hand(hand)
        d = torch.float64
        with torch.no_grad():
            poses = hand.link_poses(
                torch.as_tensor(np.asarray(palm.position, dtype=np.float64)[None], dtype=d),
                torch.as_tensor(np.asarray(palm.quaternion, dtype=np.float64)[None], dtype=d),
                torch.as_tensor(np.asarray(q, dtype=np.float64)[None], dtype=d),
            )
        lowest = np.inf
        for name, obj, verts in zip(bodies.names, bodies.objects, bodies.vertices, strict=True):
            T = poses[name][0].numpy()
            obj.setTransform(fcl.Transform(T[:3, :3], T[:3, 3]))
            if self.support is not None:
                lowest = min(lowest, self.support.clearance(verts @ T[:3, :3].T + T[:3, 3]))
        bodies.manager.update()
        hits = [PLANE] if self.support is not None and lowest < -self.support.tolerance else []
        if self._all is None:
            return hits
        data = fcl.CollisionData(request=fcl.CollisionRequest())
        self._all.collide(bodies.manager, data, fcl.defaultCollisionCallback)
        if not data.result.is_collision:
            return hits
        for name, manager in zip(self.names, self._managers, strict=True):
            data = fcl.CollisionData(request=fcl.CollisionRequest())
            manager.collide(bodies.manager, data, fcl.defaultCollisionCallback)
            if data.result.is_collision:
                hits.append(name)
        return hits
