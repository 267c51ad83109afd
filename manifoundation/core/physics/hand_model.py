"""The hand in MuJoCo, built from its description: one body per moving joint (fixed joints merged), hinge / slide
joints with the description's limits, armature and damping, a position actuator on every free joint, tied (mimic)
joints as joint equalities, every link's meshes as mesh geoms (collided as convex hulls), the palm welded to the
world at the answer's pose.

Bodies get a nominal 30 g and (1e-5 kg·m²) inertia each: with the palm welded, only the fingers' inertia matters
(revolute joints carry no armature, as the benchmark's hands; prismatic ones `Protocol.armature_prismatic`).
"""

from __future__ import annotations

from collections.abc import Collection
from dataclasses import dataclass, field

import mujoco
import numpy as np
import trimesh

from manifoundation.core.physics.hull_files import hull_file
from manifoundation.core.physics.protocol import Protocol
from manifoundation.core.robots.description import JointSpec, RobotDescription

PREFIX = "hand/"
LINK_MASS = 0.03
LINK_INERTIA = 1e-5
EXCLUDE_HOPS = 2
"""Hand bodies at most this many tree edges apart never collide with each other (covers overlapping at joints);
nor do bodies whose meshes already overlap at the rest pose (`overlapping_at_rest`)."""
HAND_SOLREF = (0.005, 1.0)
HAND_SOLIMP = (0.5, 0.99, 0.0001)


def matrix_quat(R: np.ndarray) -> np.ndarray:
    """(3, 3) rotation -> (4,) wxyz."""
    q = np.zeros(4)
    mujoco.mju_mat2Quat(q, np.ascontiguousarray(R, dtype=np.float64).reshape(9))
    return q


@dataclass
class HandModel:
    """What was built: names in the spec, and how the free joints drive every joint.

    Attributes:
        free_joints: (D,) the hand's free joints, actuated in this order.
        joints: every moving joint: (name, index of its free source joint, multiplier, offset).
        link_body: link name -> its MuJoCo body name.
        bodies: the hand's MuJoCo body names (the palm first).
    """

    free_joints: list[str]
    joints: list[tuple[str, int, float, float]] = field(default_factory=list)
    link_body: dict[str, str] = field(default_factory=dict)
    bodies: list[str] = field(default_factory=list)

    def joint_values(self, q: np.ndarray) -> dict[str, float]:
        """Every moving joint's value for free joint values q (D,)."""
        return {name: m * float(q[src]) + off for name, src, m, off in self.joints}


def add_hand(
    spec: mujoco.MjSpec, desc: RobotDescription, free_joints: list[str], palm_position: np.ndarray,
    palm_quaternion: np.ndarray, protocol: Protocol, exclude: Collection[tuple[str, str]] = (),
) -> HandModel:  # fmt: skip
    """Add the hand ``desc`` (rooted at its palm) to ``spec`` with the palm welded at the given pose (wxyz);
    ``exclude``: more pairs of body names (without the prefix) that never collide."""
    children: dict[str, list[JointSpec]] = {}
    for j in desc.joints:
        children.setdefault(j.parent, []).append(j)
    model = HandModel(list(free_joints))
    index = {n: i for i, n in enumerate(free_joints)}
    palm = spec.worldbody.add_body(name=PREFIX + desc.root, pos=palm_position, quat=palm_quaternion)
    _inertia(palm)
    model.bodies.append(palm.name)
    frames: dict[str, tuple[mujoco.MjsBody, np.ndarray]] = {desc.root: (palm, np.eye(4))}
    depth: dict[str, tuple[str, ...]] = {palm.name: (palm.name,)}  # body -> its chain from the palm
    stack = [desc.root]
    while stack:
        link = stack.pop()
        body, T = frames[link]
        _add_geoms(spec, body, link, desc, T)
        for j in children.get(link, []):
            if j.type == "fixed":
                frames[j.child] = (body, T @ j.origin)
            else:
                F = T @ j.origin
                child = body.add_body(name=PREFIX + j.child, pos=F[:3, 3], quat=matrix_quat(F[:3, :3]))
                _inertia(child)
                _add_joint(spec, child, j, protocol)
                src, mult, off = j.mimic if j.mimic is not None else (j.name, 1.0, 0.0)
                if src not in index:
                    raise ValueError(f"joint {j.name!r} is driven by {src!r}, not a free joint of the hand")
                model.joints.append((j.name, index[src], mult, off))
                if j.mimic is not None:
                    spec.add_equality(
                        type=mujoco.mjtEq.mjEQ_JOINT, name1=j.name, name2=src, objtype=mujoco.mjtObj.mjOBJ_JOINT,
                        data=[off, mult] + [0.0] * 10,
                    )  # fmt: skip
                frames[j.child] = (child, np.eye(4))
                depth[child.name] = (*depth[body.name], child.name)
                model.bodies.append(child.name)
            stack.append(j.child)
    model.link_body = {link: b.name for link, (b, _) in frames.items()}
    for name in free_joints:
        act = spec.add_actuator(name="act/" + name, target=name, trntype=mujoco.mjtTrn.mjTRN_JOINT)
        kind = spec.joint(name).type
        kp = protocol.kp_prismatic if kind == mujoco.mjtJoint.mjJNT_SLIDE else protocol.kp_revolute
        act.set_to_position(kp=kp)
    near = _exclude_near(spec, depth)
    for a, b in exclude:
        pair = (PREFIX + a, PREFIX + b)
        if pair not in near and pair[::-1] not in near:
            spec.add_exclude(bodyname1=pair[0], bodyname2=pair[1])
    return model


def overlapping_at_rest(desc: RobotDescription, free_joints: list[str], rest: np.ndarray) -> set[tuple[str, str]]:
    """Pairs of body names (without the prefix) whose meshes overlap at the rest pose ``rest`` (D,): parts
    designed to interpenetrate (covers, knuckles), never a collision the grasp caused."""
    spec = mujoco.MjSpec()
    spec.compiler.degree = False
    hm = add_hand(spec, desc, free_joints, np.zeros(3), np.array([1.0, 0.0, 0.0, 0.0]), Protocol())
    model = spec.compile()
    data = mujoco.MjData(model)
    for name, value in hm.joint_values(rest).items():
        data.qpos[model.jnt_qposadr[model.joint(name).id]] = value
    mujoco.mj_forward(model, data)
    out = set()
    for c in data.contact[: data.ncon]:
        a, b = (model.body(int(model.geom_bodyid[g])).name.removeprefix(PREFIX) for g in c.geom)
        out.add((a, b))
    return out


def _inertia(body: mujoco.MjsBody) -> None:
    body.mass = LINK_MASS
    body.inertia = [LINK_INERTIA] * 3
    body.explicitinertial = True


def _add_joint(spec: mujoco.MjSpec, body: mujoco.MjsBody, j: JointSpec, protocol: Protocol) -> None:
    slide = j.type == "prismatic"
    jt = body.add_joint(
        name=j.name, type=mujoco.mjtJoint.mjJNT_SLIDE if slide else mujoco.mjtJoint.mjJNT_HINGE, axis=j.axis,
    )  # fmt: skip
    jt.limited = mujoco.mjtLimited.mjLIMITED_TRUE
    jt.range = [j.lower, j.upper]
    jt.armature = protocol.armature_prismatic if slide else protocol.armature_revolute
    jt.damping = [protocol.damping_prismatic if slide else protocol.damping_revolute, 0.0, 0.0]


def _add_geoms(spec: mujoco.MjSpec, body: mujoco.MjsBody, link: str, desc: RobotDescription, T: np.ndarray) -> None:
    for k, mesh in enumerate(desc.links.get(link, [])):
        if len(mesh.vertices) < 4 or mesh.extents.min() < 1e-5:
            continue  # degenerate: nothing to collide
        v = _hull_vertices(mesh) @ T[:3, :3].T + T[:3, 3]  # MuJoCo collides the hull: send only its vertices
        name = f"{PREFIX}{link}/{k}"
        spec.add_mesh(name=name, file=hull_file(v))  # by file: MuJoCo's asset cache builds the hull once
        g = body.add_geom(name=name, type=mujoco.mjtGeom.mjGEOM_MESH, meshname=name)
        g.solref = list(HAND_SOLREF)
        g.solimp = [*HAND_SOLIMP, 0.5, 2.0]
        g.group = 1


def _exclude_near(spec: mujoco.MjSpec, chains: dict[str, tuple[str, ...]]) -> set[tuple[str, str]]:
    names = list(chains)
    out = set()
    for a in range(len(names)):
        for b in range(a + 1, len(names)):
            ca, cb = chains[names[a]], chains[names[b]]
            common = 0
            while common < min(len(ca), len(cb)) and ca[common] == cb[common]:
                common += 1
            hops = len(ca) + len(cb) - 2 * common
            if hops <= EXCLUDE_HOPS:
                spec.add_exclude(bodyname1=names[a], bodyname2=names[b])
                out.add((names[a], names[b]))
    return out


def _hull_vertices(mesh: trimesh.Trimesh) -> np.ndarray:
    """(k, 3) the vertices of the mesh's convex hull (trimesh caches the hull on the mesh), or all vertices when
    qhull fails (flat parts)."""
    try:
        return np.asarray(mesh.convex_hull.vertices)
    except Exception:  # qhull on degenerate input
        return np.asarray(mesh.vertices)
