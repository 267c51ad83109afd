"""Hand–object penetration on exact geometry, measured both ways.

1. Hand in object: dense points of every posed link surface (its vertices and samples about one per
   ``spacing²``) are tested inside the object mesh (ray parity, :mod:`research.audit.inside`: exact for a
   watertight object); the depth of an inside point is its distance to the object surface.
2. Object in hand: object surface samples are tested inside each link's solids (the watertight pieces
   themselves, convex hulls of the others, see :class:`research.audit.geometry.LinkGeometry`); the depth of an
   inside point is its distance to that solid's surface.

Only links whose posed bounding box comes within ``margin`` of the object's are tested (others cannot touch it).
Queries run in each link's own frame (points are moved by ``inv(world_T_link)``; distances are rigid-invariant).

Exact point-to-mesh distances are computed for the inside points that can be the deepest: the distance to the
nearest surface sample bounds each point's true depth from above, and from below up to the samples' covering
radius (taken as ``2 · spacing``), so only points within that slack of the largest bound are measured exactly
(at most :data:`MAX_EXACT` of them, the largest bounds first).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import trimesh
from scipy.spatial import cKDTree

from research.audit.geometry import LinkGeometry
from research.audit.inside import InsideTest

MAX_EXACT = 2000


@dataclass
class PenetrationAudit:
    """Where and how deep the hand and the object overlap.

    Attributes:
        depth: the largest penetration depth found (m), 0 when none.
        link: the link of the deepest point (``None`` when no penetration).
        point: (3,) world position of the deepest point (``None`` when no penetration).
        kind: ``"hand_in_object"`` or ``"object_in_link"`` for the deepest point.
        per_link: link → its deepest penetration (links tested only; 0 when none).
        tested_links: links whose bounding box reaches the object's.
        hulled_links: tested links some of whose solids are convex hulls (non-watertight pieces).
    """

    depth: float = 0.0
    link: str | None = None
    point: np.ndarray | None = None
    kind: str | None = None
    per_link: dict[str, float] = field(default_factory=dict)
    tested_links: list[str] = field(default_factory=list)
    hulled_links: list[str] = field(default_factory=list)

    def record(self, link: str, depths: np.ndarray, points: np.ndarray, kind: str) -> None:
        """Fold in inside points of ``link`` with their depths (N,) and world positions (N, 3)."""
        if depths.size == 0:
            return
        k = int(np.argmax(depths))
        self.per_link[link] = max(self.per_link.get(link, 0.0), float(depths[k]))
        if depths[k] > self.depth:
            self.depth, self.link, self.point, self.kind = float(depths[k]), link, points[k].copy(), kind


def _world_box(bounds: np.ndarray, T: np.ndarray) -> np.ndarray:
    corners = np.array([[x, y, z] for x in bounds[:, 0] for y in bounds[:, 1] for z in bounds[:, 2]])
    world = corners @ T[:3, :3].T + T[:3, 3]
    return np.stack([world.min(axis=0), world.max(axis=0)])


def _within(points: np.ndarray, box: np.ndarray, margin: float) -> np.ndarray:
    inside: np.ndarray = np.all((points >= box[0] - margin) & (points <= box[1] + margin), axis=1)
    return inside


def _to_local(points: np.ndarray, T: np.ndarray) -> np.ndarray:
    local: np.ndarray = (points - T[:3, 3]) @ T[:3, :3]
    return local


def _depths(points: np.ndarray, tree: cKDTree, surface: trimesh.Trimesh, slack: float) -> tuple[np.ndarray, np.ndarray]:
    """Exact depths of the inside ``points`` (N, 3) that can be the deepest, and their indices."""
    bound, _ = tree.query(points)
    keep = np.flatnonzero(bound >= bound.max() - slack)
    if len(keep) > MAX_EXACT:
        keep = keep[np.argsort(bound[keep])[-MAX_EXACT:]]
    _, dist, _ = trimesh.proximity.closest_point(surface, points[keep])
    return np.asarray(dist), keep


def measure_penetration(
    links: dict[str, LinkGeometry],
    poses: dict[str, np.ndarray],
    object_mesh: trimesh.Trimesh,
    *,
    spacing: float = 1e-3,
    margin: float = 2e-3,
    seed: int = 0,
) -> PenetrationAudit:
    """Penetration between the posed links and the object.

    Args:
        links: link → geometry (link frame).
        poses: link → (4, 4) world pose.
        object_mesh: the object (world frame; watertight for exact inside tests).
        spacing: sample spacing on the link and object surfaces (m).
        margin: bounding-box margin of the link selection (m).
        seed: sampling seed.

    Returns:
        The penetration found.
    """
    out = PenetrationAudit()
    obj_inside = InsideTest(object_mesh)
    obj_box = np.asarray(object_mesh.bounds, dtype=np.float64)
    count = int(np.clip(object_mesh.area / spacing**2, 1000, 60000))
    obj_samples, _ = trimesh.sample.sample_surface(object_mesh, count, seed=seed)
    obj_points = np.concatenate([np.asarray(object_mesh.vertices), obj_samples], axis=0)
    obj_tree = cKDTree(obj_points)
    slack = 2 * spacing
    for name, geom in links.items():
        T = poses[name]
        box = _world_box(np.asarray(geom.mesh.bounds, dtype=np.float64), T)
        if np.any(box[0] > obj_box[1] + margin) or np.any(box[1] < obj_box[0] - margin):
            continue
        out.tested_links.append(name)
        out.per_link[name] = 0.0
        if any(geom.hulled):
            out.hulled_links.append(name)
        # 1. the link's surface inside the object
        local = geom.surface_points(spacing, seed)
        world = local @ T[:3, :3].T + T[:3, 3]
        world = world[_within(world, obj_box, margin)]
        if len(world):
            inside = obj_inside.contains(world)
            if inside.any():
                pts = world[inside]
                depth, keep = _depths(pts, obj_tree, object_mesh, slack)
                out.record(name, depth, pts[keep], "hand_in_object")
        # 2. the object's surface inside the link's solids
        near = obj_points[_within(obj_points, box, margin)]
        if not len(near):
            continue
        near_local = _to_local(near, T)
        trees = geom.solid_trees(spacing, seed)
        for solid, test, tree in zip(geom.solids, geom.inside_tests, trees, strict=True):
            inside = test.contains(near_local)
            if inside.any():
                depth, keep = _depths(near_local[inside], tree, solid, slack)
                out.record(name, depth, near[inside][keep], "object_in_link")
    return out
