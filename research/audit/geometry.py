"""Link geometry of our own: trimesh pieces per link, built from URDF elements or a compiled MuJoCo model.

A link's geometry is the list of its pieces (one per ``<collision>``/``<visual>`` element or MJCF geom) in the
link frame, with the source used: ``"collision"`` when the link has collision elements (URDF ``<collision>``;
MJCF geoms with ``contype | conaffinity ≠ 0``), else ``"visual"`` (URDF ``<visual>``; MJCF visual-only geoms);
``prefer="visual"`` reverses the preference (visual where the link has it, else collision); ``prefer="real"``
takes a URDF link's visual meshes where its collision elements are only primitives drawn around it. Primitives are
tessellated finely (spheres: icospheres of 5120 faces; cylinders and capsules: 96 sections), which puts their
surfaces within about 0.05 mm of the exact shapes.

Inside tests use each piece as a solid: watertight pieces as they are, others by their convex hull (flagged in
:attr:`LinkGeometry.hulled`; the inside test is then conservative: it may see penetration in a concavity).
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TypeVar

import mujoco
import numpy as np
import trimesh
from numpy.typing import ArrayLike
from scipy.spatial import cKDTree

from research.audit.inside import InsideTest
from research.audit.urdf import GeometryElement, UrdfModel

SECTIONS = 96
SPHERE_SUBDIVISIONS = 4
MAX_VERTICES_KEPT = 3000


def pose_matrix(position: ArrayLike, quaternion: ArrayLike) -> np.ndarray:
    """(4, 4) pose of a position and a unit quaternion ``(w, x, y, z)`` (normalised here)."""
    quat = np.asarray(quaternion, dtype=np.float64)
    w, x, y, z = quat / np.linalg.norm(quat)
    T = np.eye(4)
    T[:3, :3] = [
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ]
    T[:3, 3] = np.asarray(position, dtype=np.float64)
    return T


def primitive(kind: str, size: np.ndarray) -> trimesh.Trimesh:
    """A primitive centred at the origin, its axis (cylinder, capsule) along z.

    Args:
        kind: ``box`` (size: (3,) full edge lengths), ``sphere`` (radius), ``cylinder`` (radius, full length),
            ``capsule`` (radius, full length of the cylindrical part), ``ellipsoid`` (3 semi-axes).
        size: the parameters above.

    Returns:
        The watertight mesh.
    """
    s = np.asarray(size, dtype=np.float64)
    mesh: trimesh.Trimesh  # trimesh.creation is untyped
    # built at unit radius, then scaled: trimesh merges vertices closer than 1e-8 and tessellations of
    # millimetre-sized shapes can lose their watertightness that way
    if kind == "box":
        mesh = trimesh.creation.box(extents=s[:3])
        return mesh
    if kind == "sphere":
        mesh = trimesh.creation.icosphere(subdivisions=SPHERE_SUBDIVISIONS, radius=1.0)
        mesh.apply_scale(float(s[0]))
    elif kind == "cylinder":
        mesh = trimesh.creation.cylinder(radius=1.0, height=float(s[1] / s[0]), sections=SECTIONS)
        mesh.apply_scale(float(s[0]))
    elif kind == "capsule":
        mesh = trimesh.creation.capsule(height=float(s[1] / s[0]), radius=1.0, count=[SECTIONS, SECTIONS // 2])
        mesh.apply_scale(float(s[0]))
    elif kind == "ellipsoid":
        mesh = trimesh.creation.icosphere(subdivisions=SPHERE_SUBDIVISIONS, radius=1.0)
        mesh.apply_scale(s[:3])
    else:
        raise ValueError(f"unsupported primitive {kind!r}")
    if not mesh.is_watertight:
        raise RuntimeError(f"tessellated {kind} {s} is not watertight")
    return mesh


def stack_meshes(meshes: list[trimesh.Trimesh]) -> trimesh.Trimesh:
    """Meshes side by side in one mesh (no vertex merging: each keeps its own topology)."""
    offsets = np.cumsum([0] + [len(m.vertices) for m in meshes[:-1]])
    verts = np.concatenate([np.asarray(m.vertices) for m in meshes])
    faces = np.concatenate([np.asarray(m.faces) + o for m, o in zip(meshes, offsets, strict=True)])
    return trimesh.Trimesh(verts, faces, process=False)


@functools.cache
def _mesh_file(path: str) -> trimesh.Trimesh:
    mesh = trimesh.load(path, force="mesh")
    if not isinstance(mesh, trimesh.Trimesh):
        raise ValueError(f"{path} is not a triangle mesh")
    # COLLADA gives each triangle corner its own vertex (for its normal and texture): welded, a closed part is
    # watertight and its own solid, not its convex hull (the Panda's finger: 564 loose triangles, then 4 closed parts)
    mesh.merge_vertices(merge_tex=True, merge_norm=True)
    return mesh


def load_mesh_file(path: Path, scale: np.ndarray | None = None) -> trimesh.Trimesh:
    """A mesh file as a trimesh (cached per file; the result is a fresh copy, scaled)."""
    mesh = _mesh_file(str(path)).copy()
    if scale is not None:
        mesh.apply_scale(np.asarray(scale, dtype=np.float64))
    return mesh


@dataclass
class LinkGeometry:
    """The geometry of one link, in the link frame.

    Attributes:
        link: link name.
        source: ``"collision"`` or ``"visual"``.
        pieces: the link's meshes (one per element / geom).
        solids: meshes for inside tests, one per piece (the piece itself, or its convex hull).
        hulled: per piece, whether its solid is a convex hull (the piece is not watertight).
    """

    link: str
    source: str
    pieces: list[trimesh.Trimesh]
    solids: list[trimesh.Trimesh] = field(init=False)
    hulled: list[bool] = field(init=False)
    _samples: dict[tuple[float, int], np.ndarray] = field(init=False, default_factory=dict, repr=False)
    _trees: dict[tuple[float, int], list[cKDTree]] = field(init=False, default_factory=dict, repr=False)

    def __post_init__(self) -> None:
        self.hulled = [not p.is_watertight for p in self.pieces]
        self.solids = [p.convex_hull if h else p for p, h in zip(self.pieces, self.hulled, strict=True)]

    @functools.cached_property
    def mesh(self) -> trimesh.Trimesh:
        """All pieces in one mesh (for distances to the link's surface and for sampling it)."""
        return stack_meshes(self.pieces) if len(self.pieces) > 1 else self.pieces[0]

    @functools.cached_property
    def inside_tests(self) -> list[InsideTest]:
        """Point-in-solid tests, one per solid (built on first use)."""
        return [InsideTest(solid) for solid in self.solids]

    @functools.cached_property
    def area(self) -> float:
        """Total surface area of the pieces (m²)."""
        return float(sum(p.area for p in self.pieces))

    def surface_points(self, spacing: float, seed: int = 0) -> np.ndarray:
        """Dense points on the link's surface: area-uniform samples and, for coarse meshes, the vertices (cached).

        Args:
            spacing: about one sample per ``spacing²`` of area (between 256 and 20000 samples).
            seed: sampling seed.

        Returns:
            (N, 3) points in the link frame.
        """
        key = (spacing, seed)
        if key not in self._samples:
            self._samples[key] = _dense_points(self.mesh, spacing, seed)
        return self._samples[key]

    def solid_trees(self, spacing: float, seed: int = 0) -> list[cKDTree]:
        """k-d trees of dense points on each solid's surface (cached), for depth bounds."""
        key = (spacing, seed)
        if key not in self._trees:
            self._trees[key] = [cKDTree(_dense_points(s, spacing, seed)) for s in self.solids]
        return self._trees[key]


def _dense_points(mesh: trimesh.Trimesh, spacing: float, seed: int) -> np.ndarray:
    """Area-uniform samples about one per ``spacing²`` (256 to 20000), plus the vertices of coarse meshes
    (corners and edges of primitives; fine meshes' vertices are dense already)."""
    count = int(np.clip(mesh.area / spacing**2, 256, 20000))
    samples, _ = trimesh.sample.sample_surface(mesh, count, seed=seed)
    if len(mesh.vertices) > MAX_VERTICES_KEPT:
        return np.asarray(samples)
    return np.concatenate([np.asarray(mesh.vertices), samples], axis=0)


_Element = TypeVar("_Element")


def _choose(collision: list[_Element], visual: list[_Element], prefer: str) -> tuple[str, list[_Element]]:
    """The preferred source where the link has it, else the other one (``"real"`` is ``"auto"`` here: a URDF
    link's choice of it is `urdf_link_geometry`'s)."""
    if prefer not in ("auto", "collision", "visual", "real"):
        raise ValueError(f"prefer must be 'auto', 'collision', 'visual' or 'real', not {prefer!r}")
    if prefer == "visual":
        return ("visual", visual) if visual else ("collision", collision)
    return ("collision", collision) if collision else ("visual", visual)


def urdf_link_geometry(
    model: UrdfModel, link: str, resolve: Callable[[str], Path], prefer: str = "auto"
) -> LinkGeometry | None:
    """The geometry of a URDF link.

    Args:
        model: the parsed URDF.
        link: the link.
        resolve: mesh ``filename`` as written in the URDF → file path.
        prefer: ``"auto"`` or ``"collision"`` (collision elements if any, else visual), ``"visual"``
            (visual elements if any, else collision), or ``"real"``: the visual meshes where every collision
            element is a primitive (a box or sphere drawn around the real part, as Allegro's), else as ``"auto"``.

    Returns:
        The link's geometry, or ``None`` when the chosen source has no element.
    """
    collision, visual = model.collisions.get(link, []), model.visuals.get(link, [])
    if prefer == "real":
        covers = bool(collision) and all(e.kind != "mesh" for e in collision)
        prefer = "visual" if covers and any(e.kind == "mesh" for e in visual) else "auto"
    source, elements = _choose(collision, visual, prefer)
    pieces = [_element_mesh(e, resolve) for e in elements]
    return LinkGeometry(link, source, pieces) if pieces else None


def _element_mesh(e: GeometryElement, resolve: Callable[[str], Path]) -> trimesh.Trimesh:
    if e.kind == "mesh":
        assert e.filename is not None
        mesh = load_mesh_file(resolve(e.filename), e.params)
    else:
        mesh = primitive(e.kind, e.params)
    mesh.apply_transform(e.origin)
    return mesh


_MJ_KINDS = {
    int(mujoco.mjtGeom.mjGEOM_SPHERE): "sphere",
    int(mujoco.mjtGeom.mjGEOM_CAPSULE): "capsule",
    int(mujoco.mjtGeom.mjGEOM_ELLIPSOID): "ellipsoid",
    int(mujoco.mjtGeom.mjGEOM_CYLINDER): "cylinder",
    int(mujoco.mjtGeom.mjGEOM_BOX): "box",
}


def mjcf_geom_mesh(model: mujoco.MjModel, g: int) -> trimesh.Trimesh:
    """Geom ``g`` of a compiled MuJoCo model as a trimesh in its body's frame (MuJoCo sizes are half sizes)."""
    kind = int(model.geom_type[g])
    size = np.asarray(model.geom_size[g], dtype=np.float64)
    if kind == int(mujoco.mjtGeom.mjGEOM_MESH):
        m = int(model.geom_dataid[g])
        v0, nv = int(model.mesh_vertadr[m]), int(model.mesh_vertnum[m])
        f0, nf = int(model.mesh_faceadr[m]), int(model.mesh_facenum[m])
        mesh = trimesh.Trimesh(model.mesh_vert[v0 : v0 + nv].astype(np.float64), model.mesh_face[f0 : f0 + nf])
    elif kind in _MJ_KINDS:
        name = _MJ_KINDS[kind]
        if name in ("capsule", "cylinder"):
            size = np.array([size[0], 2 * size[1]])  # radius, full length
        elif name == "box":
            size = 2 * size  # full edge lengths
        mesh = primitive(name, size)
    else:
        raise ValueError(f"unsupported MuJoCo geom type {kind} (geom {model.geom(g).name!r})")
    mesh.apply_transform(pose_matrix(model.geom_pos[g], model.geom_quat[g]))
    return mesh


def mjcf_link_geometry(model: mujoco.MjModel, body: int, prefer: str = "auto") -> LinkGeometry | None:
    """The geometry of an MJCF body (geoms with ``contype | conaffinity ≠ 0`` are its collision geometry).

    Args:
        model: the compiled model.
        body: body id.
        prefer: ``"auto"``, ``"collision"`` or ``"visual"`` (as for :func:`urdf_link_geometry`).

    Returns:
        The body's geometry, or ``None`` when the chosen source has no geom.
    """
    geoms = [g for g in range(model.ngeom) if int(model.geom_bodyid[g]) == body]
    collision = [g for g in geoms if int(model.geom_contype[g]) | int(model.geom_conaffinity[g])]
    visual = [g for g in geoms if g not in collision]
    source, chosen = _choose(collision, visual, prefer)
    pieces = [mjcf_geom_mesh(model, g) for g in chosen]
    return LinkGeometry(model.body(body).name, source, pieces) if pieces else None
