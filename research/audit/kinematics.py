"""Forward kinematics of our own, rooted at the palm: pytorch-kinematics for URDF, MuJoCo itself for MJCF.

Both give ``palm_T_link(q)`` for every link at or below the palm; the world pose of a link is then
``world_T_link = world_T_palm · palm_T_link(q)`` with ``palm_T_link = inv(root_T_palm) · root_T_link(q)``.
Joints above the palm (the Panda arm, Shadow's wrist) move the palm and its subtree alike and are left at zero.

Coupled joints are derived from the description itself: URDF ``<mimic joint= multiplier= offset=>`` tags, and
for MJCF the fixed coupling tendons (two joints, ``c_a·q_a + c_b·q_b ≈ 0`` within a range of at most
:data:`MJCF_COUPLING_RANGE`) and ``<equality><joint polycoef=>`` constraints (linear ones), read from the XML.
"""

from __future__ import annotations

import contextlib
import io
import xml.etree.ElementTree as ET
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import mujoco
import numpy as np
import pytorch_kinematics as pk
import torch

from research.audit.urdf import UrdfModel, read_urdf

MJCF_COUPLING_RANGE = 2e-3
"""A fixed MJCF tendon over two joints whose range lies within ± this (tendon length units) is a coupling."""


@dataclass(frozen=True)
class Coupling:
    """``joint = multiplier · source + offset`` (usable both ways when ``multiplier ≠ 0``)."""

    joint: str
    source: str
    multiplier: float
    offset: float = 0.0


class Kinematics:
    """Palm-rooted forward kinematics of a hand description.

    Attributes:
        palm: the palm link (or MJCF body).
        links: links at and below the palm.
        limits: movable joint below the palm → ``(lower, upper)``.
        couplings: the description's joint couplings.
    """

    palm: str
    links: list[str]
    limits: dict[str, tuple[float, float]]
    couplings: list[Coupling]

    def palm_transforms(self, q: Mapping[str, float]) -> dict[str, np.ndarray]:
        """``palm_T_link`` for every link at or below the palm.

        Args:
            q: a value for every movable joint in :attr:`limits` (see :func:`complete_joints`).

        Returns:
            link → (4, 4) transform in the palm frame.
        """
        raise NotImplementedError


def complete_joints(
    kin: Kinematics, given: Mapping[str, float], tol: float = 1e-6
) -> tuple[dict[str, float], list[str], list[str]]:
    """Every movable joint's value from the given ones, through the description's couplings.

    Args:
        kin: the kinematics.
        given: joint name → value as reported (free joints; coupled ones may be included).
        tol: tolerance of the consistency check of reported coupled joints.

    Returns:
        ``(values, missing, problems)``: the completed values (joints not derivable are absent), the names of
        joints neither given nor derivable, and messages for unknown names or reported values that contradict
        a coupling.
    """
    problems = [f"unknown joint {name!r}" for name in given if name not in kin.limits]
    values = {name: float(v) for name, v in given.items() if name in kin.limits}
    changed = True
    while changed:
        changed = False
        for c in kin.couplings:
            if c.source in values and c.joint not in values:
                values[c.joint] = c.multiplier * values[c.source] + c.offset
                changed = True
            elif c.joint in values and c.source not in values and c.multiplier != 0.0:
                values[c.source] = (values[c.joint] - c.offset) / c.multiplier
                changed = True
    for c in kin.couplings:
        if c.joint in given and c.source in given:
            expected = c.multiplier * float(given[c.source]) + c.offset
            if abs(float(given[c.joint]) - expected) > tol:
                problems.append(f"{c.joint} = {float(given[c.joint]):.6g} but its coupling gives {expected:.6g}")
    missing = [name for name in kin.limits if name not in values]
    return values, missing, problems


class UrdfKinematics(Kinematics):
    """FK of a URDF with pytorch-kinematics (float64), couplings from its ``<mimic>`` tags."""

    def __init__(self, path: Path, palm: str) -> None:
        """Build the chain.

        Args:
            path: the URDF file (passed to pytorch-kinematics as bytes: some files declare an encoding).
            palm: the palm link.
        """
        self.urdf: UrdfModel = read_urdf(path)
        with contextlib.redirect_stderr(io.StringIO()):  # its parser warns about unknown tags on stderr
            self.chain = pk.build_chain_from_urdf(path.read_bytes()).to(dtype=torch.float64)
        self.palm = palm
        self.links = self.urdf.subtree(palm)
        below = set(self.links[1:])
        movable = [j for j in self.urdf.joints.values() if j.type != "fixed" and j.child in below]
        self.limits = {j.name: j.limits for j in movable}
        self.couplings = [Coupling(j.name, j.mimic[0], j.mimic[1], j.mimic[2]) for j in movable if j.mimic]
        self._order = list(self.chain.get_joint_parameter_names())

    def palm_transforms(self, q: Mapping[str, float]) -> dict[str, np.ndarray]:
        """See :meth:`Kinematics.palm_transforms`."""
        th = torch.tensor([float(q.get(name, 0.0)) for name in self._order], dtype=torch.float64)
        frames = self.chain.forward_kinematics(th)
        root_T = {name: frames[name].get_matrix()[0].numpy() for name in self.links}
        inv_palm = np.linalg.inv(root_T[self.palm])
        return {name: inv_palm @ T for name, T in root_T.items()}


def _resolved_xml(path: Path) -> ET.Element:
    """The MJCF tree with ``<include file=>`` elements replaced by the included files' children."""
    root = ET.fromstring(path.read_bytes())

    def expand(element: ET.Element) -> None:
        for i, child in enumerate(list(element)):
            if child.tag == "include":
                included = ET.fromstring((path.parent / child.get("file", "")).read_bytes())
                element.remove(child)
                for k, sub in enumerate(list(included)):
                    element.insert(i + k, sub)
                expand(element)
                return
            expand(child)

    expand(root)
    return root


def mjcf_couplings(path: Path) -> list[Coupling]:
    """Joint couplings written in an MJCF file (coupling tendons, linear joint equalities).

    Args:
        path: the MJCF file (its ``<include>`` files are read too).

    Returns:
        One :class:`Coupling` per coupling tendon (``q_a = −c_b/c_a · q_b``, its first joint as ``joint``) and per
        linear ``<equality><joint joint1= joint2= polycoef=>`` (``joint1 = p0 + p1 · joint2``).
    """
    root = _resolved_xml(path)
    out = []
    for tendon in root.iter("fixed"):
        terms = [(j.get("joint", ""), float(j.get("coef", "0"))) for j in tendon.findall("joint")]
        bounds = [float(v) for v in tendon.get("range", "-inf inf").split()]
        if len(terms) == 2 and max(abs(b) for b in bounds) <= MJCF_COUPLING_RANGE and terms[0][1] != 0.0:
            (a, ca), (b, cb) = terms
            out.append(Coupling(a, b, -cb / ca))
    for eq in root.iter("equality"):
        for joint in eq.findall("joint"):
            poly = [float(v) for v in joint.get("polycoef", "0 1 0 0 0").split()]
            if joint.get("joint2") is None:
                continue  # a joint held at a constant: not a coupling
            if any(abs(p) > 0 for p in poly[2:]):
                raise ValueError(f"nonlinear joint equality {joint.get('joint1')} not supported")
            out.append(Coupling(joint.get("joint1", ""), joint.get("joint2", ""), poly[1], poly[0]))
    return out


class MjcfKinematics(Kinematics):
    """FK of an MJCF with MuJoCo itself (``mj_kinematics``; body poses ``xpos``/``xmat``)."""

    def __init__(self, path: Path, palm: str) -> None:
        """Compile the model.

        Args:
            path: the MJCF file.
            palm: the palm body.
        """
        self.model = mujoco.MjModel.from_xml_path(str(path))
        self.data = mujoco.MjData(self.model)
        self.palm = palm
        palm_id = mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_BODY, palm)
        if palm_id < 0:
            raise ValueError(f"no body {palm!r} in {path}")
        ids = [palm_id]
        for b in range(self.model.nbody):
            if b not in ids and self.model.body_parentid[b] in ids:
                ids.append(b)
        self.body_ids = ids
        self.links = [self.model.body(b).name for b in ids]
        self.limits = {}
        self._qpos_adr: dict[str, int] = {}
        for j in range(self.model.njnt):
            kind = int(self.model.jnt_type[j])
            movable = kind in (int(mujoco.mjtJoint.mjJNT_HINGE), int(mujoco.mjtJoint.mjJNT_SLIDE))
            if movable and int(self.model.jnt_bodyid[j]) in ids[1:]:
                name = self.model.joint(j).name
                lo, hi = self.model.jnt_range[j] if self.model.jnt_limited[j] else (-np.inf, np.inf)
                self.limits[name] = (float(lo), float(hi))
                self._qpos_adr[name] = int(self.model.jnt_qposadr[j])
        self.couplings = [c for c in mjcf_couplings(path) if c.joint in self.limits and c.source in self.limits]

    def palm_transforms(self, q: Mapping[str, float]) -> dict[str, np.ndarray]:
        """See :meth:`Kinematics.palm_transforms`."""
        self.data.qpos[:] = self.model.qpos0
        for name, adr in self._qpos_adr.items():
            self.data.qpos[adr] = float(q.get(name, 0.0))
        mujoco.mj_kinematics(self.model, self.data)
        world_T = {}
        for b, name in zip(self.body_ids, self.links, strict=True):
            T = np.eye(4)
            T[:3, :3] = self.data.xmat[b].reshape(3, 3)
            T[:3, 3] = self.data.xpos[b]
            world_T[name] = T
        inv_palm = np.linalg.inv(world_T[self.palm])
        return {name: inv_palm @ T for name, T in world_T.items()}
