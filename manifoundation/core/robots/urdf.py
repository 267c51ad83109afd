"""A hardened URDF reader.

A user's URDF is untrusted input: it is parsed with ``defusedxml`` (no DTDs, no entities, no external
references), capped in size and in link/joint counts, and its mesh ``filename``s are never opened (they are
ignored: only ``box``/``sphere``/``cylinder`` primitives give a user hand its collision geometry). Built-in hands
pass a ``mesh_loader`` that resolves ``package://`` and relative paths inside their own package directory.
Structural errors (cycles, missing parents, two parents, non-finite numbers, bad limits, unknown mimic sources)
raise :class:`HandLoadError` naming the element.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from collections.abc import Callable, Collection

import numpy as np
import trimesh
from defusedxml import DefusedXmlException
from defusedxml.ElementTree import fromstring

from manifoundation.core.errors import HandLoadError
from manifoundation.core.robots.description import (
    JOINT_TYPES,
    JointSpec,
    RobotDescription,
    primitive_mesh,
    transform,
)

MAX_URDF_BYTES = 2 * 1024 * 1024
"""Largest robot description (URDF or MJCF), UTF-8 bytes; the wire contract's limit too (a test keeps them equal)."""
MAX_LINKS = 256
MAX_JOINTS = 256
MAX_GEOMETRIES = 512
MAX_EXTENT = 5.0
"""Largest accepted primitive size or origin offset (m): a hand is not 5 m wide."""

MeshLoader = Callable[[str, np.ndarray], trimesh.Trimesh | None]
"""(filename, scale (3,)) -> mesh in the geometry frame, or None to skip."""


def _floats(text: str | None, n: int, what: str, default: list[float] | None = None) -> np.ndarray:
    if text is None:
        if default is None:
            raise HandLoadError(f"{what}: missing value")
        return np.asarray(default, dtype=np.float64)
    try:
        vals = [float(v) for v in text.split()]
    except ValueError as e:
        raise HandLoadError(f"{what}: not a number list: {text[:40]!r}") from e
    if len(vals) != n:
        raise HandLoadError(f"{what}: expected {n} numbers, got {len(vals)}")
    arr = np.asarray(vals, dtype=np.float64)
    if not np.all(np.isfinite(arr)):
        raise HandLoadError(f"{what}: non-finite value {text[:40]!r}")
    return arr


def _origin(elem: ET.Element | None, what: str) -> np.ndarray:
    if elem is None:
        return np.eye(4)
    xyz = _floats(elem.get("xyz"), 3, f"{what} origin xyz", [0.0, 0.0, 0.0])
    if np.any(np.abs(xyz) > MAX_EXTENT):
        raise HandLoadError(f"{what} origin xyz: offsets beyond {MAX_EXTENT} m")
    rpy = _floats(elem.get("rpy"), 3, f"{what} origin rpy", [0.0, 0.0, 0.0])
    return transform(xyz, rpy)


def _geometry(col: ET.Element, what: str, mesh_loader: MeshLoader | None) -> trimesh.Trimesh | None:
    geom = col.find("geometry")
    if geom is None or len(geom) == 0:
        raise HandLoadError(f"{what}: <collision> without <geometry>")
    shape = geom[0]
    if shape.tag == "box":
        size = _floats(shape.get("size"), 3, f"{what} box size")
        mesh = primitive_mesh("box", size)
    elif shape.tag == "sphere":
        size = _floats(shape.get("radius"), 1, f"{what} sphere radius")
        mesh = primitive_mesh("sphere", size)
    elif shape.tag == "cylinder":
        r = _floats(shape.get("radius"), 1, f"{what} cylinder radius")
        h = _floats(shape.get("length"), 1, f"{what} cylinder length")
        size = np.array([r[0], h[0]])
        mesh = primitive_mesh("cylinder", size)
    elif shape.tag == "mesh":
        if mesh_loader is None:  # untrusted: never open a path or URL named in the document
            return None
        scale = _floats(shape.get("scale"), 3, f"{what} mesh scale", [1.0, 1.0, 1.0])
        loaded = mesh_loader(shape.get("filename") or "", scale)
        if loaded is None:
            return None
        mesh = loaded
        size = np.ones(1)
    else:
        raise HandLoadError(f"{what}: unknown geometry <{shape.tag}>")
    if np.any(size <= 0) or np.any(size > MAX_EXTENT):
        raise HandLoadError(f"{what}: geometry sizes must be in (0, {MAX_EXTENT}] m")
    mesh = mesh.copy()
    mesh.apply_transform(_origin(col.find("origin"), what))
    return mesh


def parse_urdf(
    urdf: bytes | str,
    *,
    mesh_loader: MeshLoader | None = None,
    use_visual: bool = False,
    max_bytes: int = MAX_URDF_BYTES,
    only_links: Collection[str] | None = None,
) -> RobotDescription:
    """Parse (untrusted) URDF text into a :class:`RobotDescription`.

    Args:
        urdf: the document (bytes keep an XML encoding declaration valid).
        mesh_loader: resolves mesh filenames (built-ins only); None ignores every mesh element.
        use_visual: take geometry from ``<visual>`` where a link has no ``<collision>`` (descriptions that ship
            only visual meshes).
        max_bytes: size cap.
        only_links: read geometry for these links only (the others get none: a hand cut from a whole robot
            needs no meshes of its legs); None reads every link's.

    Raises:
        HandLoadError: oversized, unsafe XML, malformed or structurally inconsistent description.
    """
    data = urdf.encode() if isinstance(urdf, str) else bytes(urdf)
    if len(data) > max_bytes:
        raise HandLoadError(f"URDF is {len(data)} bytes, over the {max_bytes}-byte limit")
    try:
        root = fromstring(data, forbid_dtd=True, forbid_entities=True, forbid_external=True)
    except DefusedXmlException as e:
        raise HandLoadError(f"unsafe XML rejected ({type(e).__name__}): DTDs and entities are not allowed") from e
    except ET.ParseError as e:
        raise HandLoadError(f"malformed XML: {e}") from e
    if root.tag != "robot":
        raise HandLoadError(f"root element is <{root.tag}>, expected <robot>")
    link_elems = root.findall("link")
    joint_elems = root.findall("joint")
    if len(link_elems) > MAX_LINKS or len(joint_elems) > MAX_JOINTS:
        raise HandLoadError(
            f"{len(link_elems)} links / {len(joint_elems)} joints: over the {MAX_LINKS}/{MAX_JOINTS} limit"
        )
    if not link_elems:
        raise HandLoadError("no <link> elements")
    n_geom = sum(len(le.findall("collision")) + (len(le.findall("visual")) if use_visual else 0) for le in link_elems)
    if n_geom > MAX_GEOMETRIES:
        raise HandLoadError(f"{n_geom} geometry elements: over the {MAX_GEOMETRIES} limit")
    links: dict[str, list[trimesh.Trimesh]] = {}
    for le in link_elems:
        name = le.get("name")
        if not name:
            raise HandLoadError("a <link> has no name")
        if name in links:
            raise HandLoadError(f"link {name!r} defined twice")
        meshes: list[trimesh.Trimesh] = []
        if only_links is not None and name not in only_links:
            links[name] = meshes
            continue
        cols = le.findall("collision")
        if not cols and use_visual:
            cols = le.findall("visual")
        for i, col in enumerate(cols):
            m = _geometry(col, f"link {name!r} geometry {i}", mesh_loader)
            if m is not None:
                meshes.append(m)
        links[name] = meshes
    joints = [_joint(je, links) for je in joint_elems]
    return RobotDescription(root.get("name") or "robot", _find_root(links, joints), links, _resolve_mimic(joints))


def _joint(je: ET.Element, links: dict[str, list[trimesh.Trimesh]]) -> JointSpec:
    name = je.get("name") or ""
    jtype = je.get("type") or ""
    what = f"joint {name!r}"
    if not name:
        raise HandLoadError("a <joint> has no name")
    if jtype not in JOINT_TYPES:
        raise HandLoadError(f"{what}: unsupported type {jtype!r} (supported: {', '.join(JOINT_TYPES)})")
    parent_el, child_el = je.find("parent"), je.find("child")
    parent = parent_el.get("link") if parent_el is not None else None
    child = child_el.get("link") if child_el is not None else None
    if not parent or parent not in links:
        raise HandLoadError(f"{what}: parent link {parent!r} does not exist")
    if not child or child not in links:
        raise HandLoadError(f"{what}: child link {child!r} does not exist")
    axis = _floats(
        je.find("axis").get("xyz") if je.find("axis") is not None else None,  # type: ignore[union-attr]
        3,
        f"{what} axis",
        [1.0, 0.0, 0.0],
    )
    lower = upper = 0.0
    if jtype != "fixed":
        norm = float(np.linalg.norm(axis))
        if norm < 1e-9:
            raise HandLoadError(f"{what}: zero axis")
        axis = axis / norm
        lim = je.find("limit")
        if jtype == "continuous":
            lower, upper = -math.pi, math.pi
        elif lim is None:
            raise HandLoadError(f"{what}: {jtype} joint without <limit>")
        else:
            lower = float(_floats(lim.get("lower"), 1, f"{what} lower limit", [0.0])[0])
            upper = float(_floats(lim.get("upper"), 1, f"{what} upper limit", [0.0])[0])
            if lower > upper:
                raise HandLoadError(f"{what}: lower limit {lower} > upper limit {upper}")
    mimic = None
    mi = je.find("mimic")
    if mi is not None and jtype != "fixed":
        src = mi.get("joint")
        if not src:
            raise HandLoadError(f"{what}: <mimic> without joint")
        mult = float(_floats(mi.get("multiplier"), 1, f"{what} mimic multiplier", [1.0])[0])
        off = float(_floats(mi.get("offset"), 1, f"{what} mimic offset", [0.0])[0])
        mimic = (src, mult, off)
    return JointSpec(name, jtype, parent, child, _origin(je.find("origin"), what), axis, lower, upper, mimic)


def _find_root(links: dict[str, list[trimesh.Trimesh]], joints: list[JointSpec]) -> str:
    parent_of: dict[str, str] = {}
    names = set()
    for j in joints:
        if j.name in names:
            raise HandLoadError(f"joint {j.name!r} defined twice")
        names.add(j.name)
        if j.child in parent_of:
            raise HandLoadError(f"link {j.child!r} has two parent joints")
        parent_of[j.child] = j.parent
    for start in parent_of:  # walk up from every link: a revisit is a cycle
        seen = {start}
        cur = start
        while cur in parent_of:
            cur = parent_of[cur]
            if cur in seen:
                raise HandLoadError(f"kinematic cycle through link {cur!r}")
            seen.add(cur)
    roots = [n for n in links if n not in parent_of]
    if len(roots) != 1:
        raise HandLoadError(f"expected one root link, found {len(roots)}: {roots[:5]}")
    return roots[0]


def _resolve_mimic(joints: list[JointSpec]) -> list[JointSpec]:
    by_name = {j.name: j for j in joints}
    for j in joints:
        if j.mimic is None:
            continue
        src, mult, off = j.mimic
        if src not in by_name or by_name[src].type == "fixed":
            raise HandLoadError(f"joint {j.name!r}: mimics unknown or fixed joint {src!r}")
        depth = 0
        while by_name[src].mimic is not None:  # flatten chains of mimics onto the free joint
            s2, m2, o2 = by_name[src].mimic  # type: ignore[misc]
            src, mult, off = s2, mult * m2, mult * o2 + off
            depth += 1
            if depth > len(joints):
                raise HandLoadError(f"joint {j.name!r}: cyclic mimic chain")
        j.mimic = (src, mult, off)
    return joints
