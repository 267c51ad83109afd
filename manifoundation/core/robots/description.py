"""A parsed robot description: links with collision meshes and the joints between them.

Both the URDF and the MJCF readers produce a :class:`RobotDescription`; :mod:`manifoundation.core.robots.kinematics`
turns it into a tree of moving bodies (fixed joints collapsed) for batched forward kinematics.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field

import numpy as np
import trimesh

from manifoundation.core.errors import HandLoadError

JOINT_TYPES = ("fixed", "revolute", "continuous", "prismatic")


@dataclass
class JointSpec:
    """One joint: ``child`` pose = ``parent`` pose @ ``origin`` @ motion(value about/along ``axis``).

    ``mimic`` = (source joint name, multiplier, offset): value = multiplier * source + offset.
    """

    name: str
    type: str
    parent: str
    child: str
    origin: np.ndarray  # (4, 4) parent link frame -> joint frame
    axis: np.ndarray  # (3,) unit, in the joint frame
    lower: float = 0.0
    upper: float = 0.0
    mimic: tuple[str, float, float] | None = None


@dataclass
class RobotDescription:
    """Links (each with its collision meshes, in the link frame) and joints, rooted at ``root``."""

    name: str
    root: str
    links: dict[str, list[trimesh.Trimesh]] = field(default_factory=dict)
    joints: list[JointSpec] = field(default_factory=list)
    couplings: list[str] = field(default_factory=list)
    """What the reader did with each coupling the file declares (mimic, tendon, equality), one line each."""

    def subtree(self, root: str) -> RobotDescription:
        """The description restricted to ``root`` and its descendants (e.g. the hand of an arm)."""
        if root not in self.links:
            raise HandLoadError(f"root link {root!r} is not a link of {self.name!r}")
        children: dict[str, list[JointSpec]] = {}
        for j in self.joints:
            children.setdefault(j.parent, []).append(j)
        keep_links = [root]
        keep_joints: list[JointSpec] = []
        stack = [root]
        while stack:
            for j in children.get(stack.pop(), []):
                keep_links.append(j.child)
                keep_joints.append(j)
                stack.append(j.child)
        kept = {j.name for j in keep_joints} | set(keep_links)
        couplings = [c for c in self.couplings if kept & set(re.findall(r"[^\s'\"(),=*]+", c))]
        return RobotDescription(self.name, root, {k: self.links[k] for k in keep_links}, keep_joints, couplings)


def transform(xyz: np.ndarray | None = None, rpy: np.ndarray | None = None) -> np.ndarray:
    """A 4x4 transform from a translation and URDF roll-pitch-yaw (R = Rz(yaw) Ry(pitch) Rx(roll))."""
    T = np.eye(4)
    if rpy is not None:
        r, p, y = (float(v) for v in rpy)
        cr, sr, cp, sp, cy, sy = np.cos(r), np.sin(r), np.cos(p), np.sin(p), np.cos(y), np.sin(y)
        T[:3, :3] = np.array(
            [
                [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
                [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
                [-sp, cp * sr, cp * cr],
            ]
        )
    if xyz is not None:
        T[:3, 3] = xyz
    return T


def primitive_mesh(kind: str, size: np.ndarray) -> trimesh.Trimesh:
    """A watertight mesh for a primitive centred at the origin (z the axis of cylinders and capsules).

    ``size``: box (3,) full extents; sphere (1,) radius; cylinder/capsule (2,) radius, full length of the
    straight part.
    """
    mesh: trimesh.Trimesh  # trimesh.creation is untyped
    if kind == "box":
        mesh = trimesh.creation.box(extents=size[:3])
    elif kind == "sphere":
        mesh = trimesh.creation.icosphere(subdivisions=2, radius=float(size[0]))
    elif kind == "cylinder":
        mesh = trimesh.creation.cylinder(radius=float(size[0]), height=float(size[1]), sections=24)
    elif kind == "capsule":
        mesh = trimesh.creation.capsule(radius=float(size[0]), height=float(size[1]), count=[16, 16])
    else:
        raise HandLoadError(f"unknown primitive {kind!r}")
    return mesh
