"""A simulation body from a caller's cloud: what the service simulates when a request asks for the rollout.

A request carries only an oriented point cloud (and its material and properties), while `simulate` needs a
simulation mesh. Per material:

- **Cloth** lies flat: its points become the mesh's vertices, triangulated by Delaunay in the best-fit plane,
  minus the triangles across gaps (an edge longer than ``GAP`` × the median nearest-neighbour spacing) and the
  slivers; the cloud is the vertices themselves.
- **Rope**: the centre line is recovered from the cloud (the geodesic parameter along a k-nearest-neighbour
  graph from one end to the other, binned into stations) and rebuilt as the same square rod of tetrahedra the
  generator makes (`manifoundation.core.deformable.rope.rod`), its thickness the cloud's.
- **Plasticine**: a cloud that is the boundary of a body cut from an axis-aligned cubic lattice (the generator's
  bodies) is rebuilt as exactly that body (`manifoundation.core.deformable.lattice_fit`); any other cloud's volume
  (generalised winding number ≥ ½) is filled with lattice tetrahedra of its own
  (`manifoundation.core.deformable.plasticine.tetrahedralise`, the cubes whose centre is inside, so that the body's
  volume is about the cloud's), refined until it holds enough cubes.

For rope and plasticine the caller's points are not the mesh's vertices: each point is embedded in its nearest
tetrahedron by barycentric (affine) weights, and its rollout position is the same weights over the moved
vertices. The body rests on a table under its lowest point (the simulator's table is z = 0; the cloud is shifted
down and the rollout back up). `tests/core/deformable/test_reconstruct.py` compares rollouts of reconstructed
bodies with those of the generators' own meshes under the same manipulation.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import connected_components, dijkstra
from scipy.spatial import Delaunay, cKDTree

from manifoundation.core.deformable.body import DeformableBody
from manifoundation.core.deformable.materials import ROPE_RADIUS
from manifoundation.core.errors import InvalidInput

GAP = 2.5  # cloth: drop triangles with an edge longer than this × the median spacing
FLATNESS = 0.1  # cloth: largest out-of-plane spread allowed, as a fraction of the cloth's size
TABLE_CLEARANCE = 1e-3  # m between the table and the body's lowest point
NEIGHBOURS = 8
PLASTICINE_CELLS = (8, 16)  # lattice cells across the longest side: first try, last try
MIN_TETS = 48


@dataclass(frozen=True)
class EmbeddedCloud:
    """A simulation body and where the caller's N points sit in it.

    Attributes:
        body: the simulation body (vertices in the simulator's frame: the table at z = 0).
        corners: (N, k) vertex indices of each point's element (k = 1 for points that are vertices).
        weights: (N, k) barycentric weights over ``corners`` (rows sum to 1).
        offset: (3,) what was added to the caller's points to put them in the simulator's frame.
    """

    body: DeformableBody
    corners: np.ndarray
    weights: np.ndarray
    offset: np.ndarray

    def cloud(self, vertices: np.ndarray) -> np.ndarray:
        """(N, 3) the caller's points, in the caller's frame, carried by the body's moved ``vertices`` (V, 3)."""
        v = np.asarray(vertices, dtype=np.float64)
        carried: np.ndarray = np.einsum("nk,nkd->nd", self.weights, v[self.corners]) - self.offset
        return carried

    def to_simulator(self, points: np.ndarray) -> np.ndarray:
        """(M, 3) caller-frame points in the simulator's frame."""
        shifted: np.ndarray = np.asarray(points, dtype=np.float64) + self.offset
        return shifted


def body_from_cloud(material: str, points: np.ndarray, normals: np.ndarray,
                    properties: dict[str, float]) -> EmbeddedCloud:  # fmt: skip
    """The simulation body of a cloud of ``material`` (see the module doc).

    Args:
        material: cloth, rope or plasticine.
        points: (N, 3) the object's points, m.
        normals: (N, 3) their outward unit normals (used for plasticine's inside test).
        properties: the material's contract properties.

    Raises:
        InvalidInput: the cloud cannot be that material's body (a cloth that is not flat, a rope in pieces, a
            plasticine cloud that encloses no volume), naming ``object.points``.
    """
    p = np.asarray(points, dtype=np.float64)
    offset = np.array([0.0, 0.0, TABLE_CLEARANCE - float(p[:, 2].min())])
    q = p + offset
    if material == "cloth":
        body = _cloth(q, properties)
        n = len(q)
        return EmbeddedCloud(body, np.arange(n)[:, None], np.ones((n, 1)), offset)
    if material == "rope":
        body = _rope(q, properties)
        corners, weights = _embed(body, q)
        return EmbeddedCloud(body, corners, weights, offset)
    if material != "plasticine":
        raise InvalidInput(f"object.material: {material!r} is not deformable")
    # built and embedded where the cloud is, then set on the table by its own lowest vertex
    body = _plasticine(p, np.asarray(normals, dtype=np.float64), properties)
    corners, weights = _embed(body, p)
    offset = np.array([0.0, 0.0, TABLE_CLEARANCE - float(np.min(body.vertices[:, 2]))])
    moved = DeformableBody("plasticine", "cloud", body.vertices + offset, body.elements, body.surface, body.normals,
                           body.properties)  # fmt: skip
    return EmbeddedCloud(moved, corners, weights, offset)


def _spacing(points: np.ndarray) -> float:
    d, _ = cKDTree(points).query(points, k=2)
    return float(np.median(d[:, 1]))


def _cloth(points: np.ndarray, properties: dict[str, float]) -> DeformableBody:
    centre = points.mean(axis=0)
    vt = np.linalg.svd(points - centre, full_matrices=False)[2]
    uv = (points - centre) @ vt[:2].T
    size = float(np.ptp(uv, axis=0).max())
    spread = float(np.ptp((points - centre) @ vt[2]))
    if spread > FLATNESS * size:
        raise InvalidInput(f"object.points: a cloth rollout needs the cloth lying flat; it spreads {spread:.3f} m "
                           f"out of its plane ({size:.3f} m across)")  # fmt: skip
    tri = Delaunay(uv).simplices
    a, b, c = (uv[tri[:, i]] for i in range(3))
    edges = np.stack([np.linalg.norm(a - b, axis=1), np.linalg.norm(b - c, axis=1), np.linalg.norm(c - a, axis=1)])
    area = 0.5 * np.abs((b - a)[:, 0] * (c - a)[:, 1] - (b - a)[:, 1] * (c - a)[:, 0])
    h = _spacing(uv)
    keep = (edges.max(axis=0) <= GAP * h) & (area >= 0.1 * h * h)
    if keep.sum() < 2:
        raise InvalidInput("object.points: the cloth's points form no triangles (too sparse or collinear)")
    normals = np.tile(np.sign(vt[2, 2] or 1.0) * vt[2], (len(points), 1))
    return DeformableBody("cloth", "cloud", points, tri[keep], np.arange(len(points)), normals, dict(properties))


def _geodesic_order(points: np.ndarray) -> np.ndarray:
    """Each point's distance (m) along the k-nearest-neighbour graph from one end of the cloud."""
    n = len(points)
    k = min(NEIGHBOURS, n - 1)
    d, j = cKDTree(points).query(points, k=k + 1)
    graph = csr_matrix((d[:, 1:].ravel(), (np.repeat(np.arange(n), k), j[:, 1:].ravel())), shape=(n, n))
    graph = graph.maximum(graph.T)
    if connected_components(graph, directed=False)[0] != 1:
        raise InvalidInput("object.points: a rope rollout needs one connected rope; the cloud falls into pieces")
    first = int(np.argmax(dijkstra(graph, indices=0)))
    return np.asarray(dijkstra(graph, indices=first))


def _rope(points: np.ndarray, properties: dict[str, float]) -> DeformableBody:
    from manifoundation.core.deformable.rope import STATION_SPACING, rod

    t = _geodesic_order(points)
    radius = float(np.clip(0.5 * np.ptp(points[:, 2]), 0.5 * ROPE_RADIUS, 10 * ROPE_RADIUS))
    spacing = STATION_SPACING * radius / ROPE_RADIUS
    bins = np.floor(t / spacing).astype(np.int64)
    line = np.stack([points[bins == b, :2].mean(axis=0) for b in np.unique(bins)])
    if len(line) < 2:
        raise InvalidInput("object.points: the rope is shorter than two of its stations")
    verts, tets, normals = rod(line, radius)
    return DeformableBody("rope", "cloud", verts, tets, np.arange(len(verts)), normals, dict(properties))


def _plasticine(points: np.ndarray, normals: np.ndarray, properties: dict[str, float]) -> DeformableBody:
    from manifoundation.core.deformable.lattice import boundary
    from manifoundation.core.deformable.lattice_fit import lattice_body
    from manifoundation.core.deformable.plasticine import tetrahedralise
    from manifoundation.core.refine.field import PointCloudField

    exact = lattice_body(points, normals)
    if exact is not None:  # the cloud is a lattice body's boundary: that body
        return DeformableBody("plasticine", "cloud", exact.vertices, exact.tetrahedra, exact.surface,
                              exact.surface_normals, dict(properties))  # fmt: skip
    field = PointCloudField(points, normals)
    lo, hi = points.min(axis=0), points.max(axis=0)
    centre, side = 0.5 * (lo + hi), float((hi - lo).max()) * 1.02

    def inside(unit: np.ndarray) -> np.ndarray:
        return np.asarray(field.winding_number(centre + unit * side) >= 0.5)

    for cells in range(PLASTICINE_CELLS[0], PLASTICINE_CELLS[1] + 1, 2):
        try:
            unit, tets = tetrahedralise(inside, cells, keep="centres")
        except ValueError:
            continue
        if len(tets) >= MIN_TETS:
            verts = centre + unit * side
            surface, surface_normals = boundary(verts, tets)
            return DeformableBody("plasticine", "cloud", verts, tets, surface, surface_normals, dict(properties))
    raise InvalidInput("object.points: a plasticine rollout needs a closed, outward-oriented cloud; this one "
                       "encloses no volume the simulator can fill")  # fmt: skip


def _embed(body: DeformableBody, points: np.ndarray, candidates: int = 8) -> tuple[np.ndarray, np.ndarray]:
    """(N, 4) corners and barycentric weights of each point in the best of its nearest tetrahedra.

    "Best" is the tetrahedron whose smallest weight is largest: the one containing the point when one does,
    else the one it lies least outside of (the weights then extrapolate affinely).
    """
    v, tets = np.asarray(body.vertices, dtype=np.float64), np.asarray(body.elements)
    k = min(candidates, len(tets))
    _, near = cKDTree(v[tets].mean(axis=1)).query(points, k=k)
    near = near.reshape(len(points), k)
    corner = v[tets[near]]  # (N, k, 4, 3)
    basis = np.swapaxes(corner[:, :, 1:] - corner[:, :, :1], -1, -2)  # (N, k, 3, 3), columns = edges
    local = np.linalg.solve(basis, (points[:, None, :] - corner[:, :, 0])[..., None])[..., 0]
    weights = np.concatenate([1.0 - local.sum(axis=-1, keepdims=True), local], axis=-1)  # (N, k, 4)
    best = np.argmax(weights.min(axis=-1), axis=1)
    rows = np.arange(len(points))
    return tets[near[rows, best]], weights[rows, best]
