"""A small URDF reader of our own: link geometry elements and joints (with ``<mimic>``), read with ``xml.etree``.

Only for the packaged, trusted description files of the built-in hands. Kinematics themselves come from
pytorch-kinematics (see :mod:`research.audit.kinematics`); this reader supplies what pytorch-kinematics drops:
every ``<collision>``/``<visual>`` element of a link (it keeps one visual only) and the ``<mimic>`` tags.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np


def rpy_matrix(rpy: np.ndarray) -> np.ndarray:
    """Rotation of URDF roll-pitch-yaw angles, ``Rz(yaw) · Ry(pitch) · Rx(roll)``.

    Args:
        rpy: (3,) roll, pitch, yaw in radians.

    Returns:
        (3, 3) rotation matrix.
    """
    r, p, y = (float(a) for a in rpy)
    cr, sr, cp, sp, cy, sy = np.cos(r), np.sin(r), np.cos(p), np.sin(p), np.cos(y), np.sin(y)
    rx = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
    ry = np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
    rz = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
    rot: np.ndarray = rz @ ry @ rx
    return rot


def origin_matrix(element: ET.Element | None) -> np.ndarray:
    """(4, 4) transform of an ``<origin xyz= rpy=>`` element (identity when absent)."""
    T = np.eye(4)
    if element is None:
        return T
    T[:3, :3] = rpy_matrix(_floats(element.get("rpy"), 3))
    T[:3, 3] = _floats(element.get("xyz"), 3)
    return T


def _floats(text: str | None, n: int, default: float = 0.0) -> np.ndarray:
    if text is None:
        return np.full(n, default, dtype=np.float64)
    values = np.array([float(v) for v in text.split()], dtype=np.float64)
    if values.shape != (n,):
        raise ValueError(f"expected {n} numbers, got {text!r}")
    return values


@dataclass(frozen=True)
class GeometryElement:
    """One ``<collision>`` or ``<visual>`` element of a link.

    Attributes:
        kind: ``"box"``, ``"sphere"``, ``"cylinder"`` or ``"mesh"``.
        origin: (4, 4) element pose in the link frame.
        params: box ``size`` (3,), sphere ``radius`` (1,), cylinder ``radius, length`` (2,), mesh ``scale`` (3,).
        filename: the mesh file name as written in the URDF (meshes only).
    """

    kind: str
    origin: np.ndarray
    params: np.ndarray
    filename: str | None = None


@dataclass(frozen=True)
class UrdfJoint:
    """A URDF joint.

    Attributes:
        name: joint name.
        type: ``revolute``, ``continuous``, ``prismatic`` or ``fixed`` (others are refused).
        parent: parent link.
        child: child link.
        origin: (4, 4) joint origin in the parent link frame.
        axis: (3,) unit joint axis in the joint frame.
        limits: ``(lower, upper)``; ``(-inf, inf)`` for continuous or unlimited joints.
        mimic: ``(joint, multiplier, offset)`` of a ``<mimic>`` tag, else ``None``.
    """

    name: str
    type: str
    parent: str
    child: str
    origin: np.ndarray
    axis: np.ndarray
    limits: tuple[float, float]
    mimic: tuple[str, float, float] | None = None


@dataclass
class UrdfModel:
    """Links (with their geometry elements) and joints of a URDF.

    Attributes:
        name: robot name.
        collisions: link → its ``<collision>`` elements (possibly empty).
        visuals: link → its ``<visual>`` elements (possibly empty).
        joints: joints by name, in document order.
    """

    name: str
    collisions: dict[str, list[GeometryElement]] = field(default_factory=dict)
    visuals: dict[str, list[GeometryElement]] = field(default_factory=dict)
    joints: dict[str, UrdfJoint] = field(default_factory=dict)

    @property
    def root(self) -> str:
        """The link that is nobody's child."""
        children = {j.child for j in self.joints.values()}
        roots = [link for link in self.collisions if link not in children]
        if len(roots) != 1:
            raise ValueError(f"URDF {self.name!r} has {len(roots)} root links: {roots}")
        return roots[0]

    def subtree(self, link: str) -> list[str]:
        """Links at and below ``link`` (``link`` first)."""
        out, stack = [], [link]
        while stack:
            current = stack.pop()
            out.append(current)
            stack.extend(j.child for j in self.joints.values() if j.parent == current)
        return out


def _geometry(element: ET.Element) -> GeometryElement | None:
    geometry = element.find("geometry")
    if geometry is None or len(geometry) == 0:
        return None
    shape = geometry[0]
    origin = origin_matrix(element.find("origin"))
    if shape.tag == "box":
        return GeometryElement("box", origin, _floats(shape.get("size"), 3))
    if shape.tag == "sphere":
        return GeometryElement("sphere", origin, np.array([float(shape.get("radius", "0"))]))
    if shape.tag == "cylinder":
        params = np.array([float(shape.get("radius", "0")), float(shape.get("length", "0"))])
        return GeometryElement("cylinder", origin, params)
    if shape.tag == "mesh":
        return GeometryElement("mesh", origin, _floats(shape.get("scale"), 3, 1.0), shape.get("filename"))
    raise ValueError(f"unsupported URDF geometry <{shape.tag}>")


def read_urdf(path: Path) -> UrdfModel:
    """Parse a URDF file.

    Args:
        path: the URDF file.

    Returns:
        Its links' geometry elements and its joints.

    Raises:
        ValueError: unsupported joint type or geometry, malformed numbers.
    """
    root = ET.fromstring(path.read_bytes())
    model = UrdfModel(name=root.get("name", path.stem))
    for link in root.findall("link"):
        name = link.get("name", "")
        model.collisions[name] = [g for e in link.findall("collision") if (g := _geometry(e)) is not None]
        model.visuals[name] = [g for e in link.findall("visual") if (g := _geometry(e)) is not None]
    for joint in root.findall("joint"):
        kind = joint.get("type", "")
        if kind not in {"revolute", "continuous", "prismatic", "fixed"}:
            raise ValueError(f"unsupported joint type {kind!r}")
        limit = joint.find("limit")
        lo, hi = -np.inf, np.inf
        if limit is not None and kind in {"revolute", "prismatic"}:
            lo, hi = float(limit.get("lower", "0")), float(limit.get("upper", "0"))
        mimic_el = joint.find("mimic")
        mimic = None
        if mimic_el is not None:
            mimic = (
                mimic_el.get("joint", ""),
                float(mimic_el.get("multiplier", "1")),
                float(mimic_el.get("offset", "0")),
            )
        axis_el = joint.find("axis")
        axis = _floats(axis_el.get("xyz", "1 0 0") if axis_el is not None else "1 0 0", 3)
        model.joints[joint.get("name", "")] = UrdfJoint(
            name=joint.get("name", ""),
            type=kind,
            parent=joint.find("parent").get("link", ""),  # type: ignore[union-attr]
            child=joint.find("child").get("link", ""),  # type: ignore[union-attr]
            origin=origin_matrix(joint.find("origin")),
            axis=axis / np.linalg.norm(axis),
            limits=(lo, hi),
            mimic=mimic,
        )
    return model
