"""The object in MuJoCo: convex pieces of its surface on one free body of the protocol's mass.

MuJoCo collides a mesh as its convex hull, so a non-convex object needs pieces (DexGraspBench uses CoACD's; no
decomposition library is a dependency here). Ours:

- a mesh that is (nearly) convex (watertight, volume ≥ ``CONVEX_RATIO`` of its hull's) is its hull, exactly;
- a point cloud that lies on its own convex hull (every point within ``HULL_TOLERANCE`` of the hull's surface) is
  that hull ("point_hull"): a convex object sent as points is then built as the mesh's hull would be (on 43
  third-party objects, 24 are convex; the patches below let 3 of 10 LEAP answers that held on them fail on the
  exact hull, research/results/physics.md);
- any other mesh, and any other point cloud (points + outward normals), becomes ``PATCHES`` surface patches (k-means of
  surface samples), each thickened inward along its normals by ``min(1 cm, 20 % of the smallest extent)``: the
  pieces follow the surface (concavities stay open up to the patches' size) and are solid under it.

Mass ``protocol.mass`` and the inertia of the object's hull (uniform density) are set explicitly.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np
import trimesh
from scipy.cluster.vq import kmeans2
from scipy.spatial import ConvexHull, QhullError

from manifoundation.core.physics.protocol import Protocol

CONVEX_RATIO = 0.9
HULL_TOLERANCE = 1e-3
"""m: a point cloud whose points all lie within this of its convex hull's surface is built as that hull."""
HULL_CHUNK = 256
"""Points measured against the hull's facets at a time (`_hull_of`: 2 048 points × thousands of facets measured at
once took 15 ms on average, most of it for clouds whose first chunk already fails)."""
PATCHES = 24
SAMPLES = 3000
OBJECT = "object"


@dataclass
class ObjectShape:
    """Convex pieces (each (k, 3) vertices, world frame) and how they were made ("hull", "mesh_patches",
    "point_hull", "point_patches")."""

    pieces: list[np.ndarray]
    source: str

    @property
    def centre(self) -> np.ndarray:
        """(3,) centre of the pieces' bounding box."""
        allv = np.vstack(self.pieces)
        return np.asarray(0.5 * (allv.min(0) + allv.max(0)))


def from_mesh(vertices: np.ndarray, faces: np.ndarray, seed: int = 0) -> ObjectShape:
    """Pieces of a triangle mesh (V, 3), (F, 3)."""
    mesh = trimesh.Trimesh(np.asarray(vertices, float), np.asarray(faces, np.int64), process=True)
    hull = mesh.convex_hull
    if mesh.is_watertight and hull.volume > 0 and abs(mesh.volume) >= CONVEX_RATIO * hull.volume:
        return ObjectShape([np.asarray(hull.vertices)], "hull")
    rng = np.random.default_rng(seed)
    areas = mesh.area_faces
    face = rng.choice(len(areas), SAMPLES, p=areas / areas.sum())
    uv = rng.random((SAMPLES, 2))
    flip = uv.sum(1) > 1
    uv[flip] = 1 - uv[flip]
    tri = mesh.triangles[face]
    pts = tri[:, 0] + uv[:, :1] * (tri[:, 1] - tri[:, 0]) + uv[:, 1:] * (tri[:, 2] - tri[:, 0])
    normals = mesh.face_normals[face]
    return ObjectShape(_patches(pts, normals, seed), "mesh_patches")


def from_points(points: np.ndarray, normals: np.ndarray, seed: int = 0) -> ObjectShape:
    """Pieces of a surface point cloud (N, 3) with outward unit normals (N, 3): its hull when the points lie on it
    (`HULL_TOLERANCE`), else patches."""
    points = np.asarray(points, float)
    hull = _hull_of(points)
    if hull is not None:
        return ObjectShape([hull], "point_hull")
    return ObjectShape(_patches(points, np.asarray(normals, float), seed), "point_patches")


def _hull_of(points: np.ndarray) -> np.ndarray | None:
    """(k, 3) the vertices of the convex hull of ``points`` (N, 3) when every point lies within `HULL_TOLERANCE` of
    the hull's surface, else None. Inside a convex polytope the distance to its surface is the distance to the
    nearest facet plane."""
    try:
        hull = ConvexHull(points)
    except QhullError:  # flat or degenerate clouds
        return None
    inner = np.ones(len(points), dtype=bool)
    inner[hull.vertices] = False  # a vertex lies on the surface: only the other points need measuring
    rest = points[inner]
    for start in range(0, len(rest), HULL_CHUNK):  # a non-convex cloud usually fails in its first chunk
        chunk = rest[start : start + HULL_CHUNK]
        depth = -(chunk @ hull.equations[:, :3].T + hull.equations[:, 3]).max(axis=1)  # (c,) ≥ 0 inside
        if float(depth.max()) > HULL_TOLERANCE:
            return None
    vertices: np.ndarray = points[hull.vertices]
    return vertices


def _patches(points: np.ndarray, normals: np.ndarray, seed: int) -> list[np.ndarray]:
    extent = points.max(0) - points.min(0)
    depth = min(0.01, 0.2 * float(extent.min()) if extent.min() > 0 else 0.01)
    k = min(PATCHES, max(1, len(points) // 8))
    _, label = kmeans2(points, k, minit="++", seed=seed)
    pieces = []
    for c in range(k):
        sel = label == c
        if sel.sum() < 3:
            continue
        p, n = points[sel], normals[sel]
        pieces.append(np.vstack([p, p - depth * n]))
    return pieces


def add_object(spec: mujoco.MjSpec, shape: ObjectShape, protocol: Protocol) -> mujoco.MjsBody:
    """A free body ``object`` at the pieces' centre with one mesh geom per piece, of ``protocol.mass``."""
    centre = shape.centre
    body = spec.worldbody.add_body(name=OBJECT, pos=centre)
    body.add_freejoint(name=OBJECT + "/free")
    for i, piece in enumerate(shape.pieces):
        name = f"{OBJECT}/{i}"
        spec.add_mesh(name=name, uservert=(piece - centre).astype(np.float32).reshape(-1).tolist())
        body.add_geom(name=name, type=mujoco.mjtGeom.mjGEOM_MESH, meshname=name)
    hull = trimesh.convex.convex_hull(np.vstack(shape.pieces) - centre)
    body.mass = protocol.mass
    if hull.volume > 1e-12:
        inertia = np.asarray(hull.moment_inertia) * protocol.mass / hull.volume
        body.ipos = np.asarray(hull.center_mass)
    else:
        inertia = np.eye(3) * protocol.mass * 1e-4
        body.ipos = np.zeros(3)
    body.fullinertia = [inertia[0, 0], inertia[1, 1], inertia[2, 2], inertia[0, 1], inertia[0, 2], inertia[1, 2]]
    body.explicitinertial = True
    return body
