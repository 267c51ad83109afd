"""MJCF (MuJoCo) descriptions for built-in hands that ship only as MJCF (Shadow).

The file is compiled by ``mujoco`` itself (defaults, classes, includes, mesh assets), then its body tree is read
back into a :class:`RobotDescription`: one link per body, hinge → revolute, slide → prismatic, geoms with
``contype | conaffinity`` ≠ 0 as collision meshes. A fixed tendon over two joints with a range of at most
``COUPLING_RANGE`` (Shadow's ``T_xxJ1c``: c0·J0 + c1·J1 ≈ 0) ties its first joint to its second
(J0 = −c1/c0 · J1): we treat it as an exact mimic joint.

Only for trusted, packaged files: ``mujoco`` opens the meshes the MJCF names.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import trimesh

from manifoundation.core.errors import HandLoadError
from manifoundation.core.robots.description import JointSpec, RobotDescription, primitive_mesh

if TYPE_CHECKING:
    import mujoco  # untyped (no stubs): its objects read as Any

COUPLING_RANGE = 2e-3


def _quat_matrix(q: np.ndarray) -> np.ndarray:
    w, x, y, z = q / np.linalg.norm(q)
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


def _T(pos: np.ndarray, quat: np.ndarray) -> np.ndarray:
    T = np.eye(4)
    T[:3, :3] = _quat_matrix(np.asarray(quat, dtype=np.float64))
    T[:3, 3] = pos
    return T


def parse_mjcf(path: str, name: str = "robot") -> RobotDescription:
    """Compile the MJCF at ``path`` with mujoco and return its body tree as a description (root = world)."""
    import mujoco

    return description_from_model(mujoco.MjModel.from_xml_path(path), name)


def description_from_model(m: mujoco.MjModel, name: str = "robot", *, body_frames: bool = False) -> RobotDescription:
    """The body tree of a compiled ``mujoco.MjModel`` as a description (root = world).

    Joint ``ref`` values are honoured (a joint at its ``ref`` leaves the body where the file puts it, so joint
    values mean what they mean in MuJoCo).

    Args:
        m: the compiled model.
        name: the description's name.
        body_frames: give every body a link in its own MuJoCo frame (joint frames become extra ``<body>__j<k>``
            links, collapsed by the kinematics): palm poses and link frames then agree with MuJoCo's. Without
            it a jointed body's link is its last joint's frame (the built-in Shadow's fingertip offsets use it).
    """
    import mujoco

    def nm(obj: mujoco.mjtObj, i: int) -> str:
        return mujoco.mj_id2name(m, obj, i) or f"{obj.name}_{i}"

    links: dict[str, list[trimesh.Trimesh]] = {nm(mujoco.mjtObj.mjOBJ_BODY, b): [] for b in range(m.nbody)}
    correction: dict[int, np.ndarray] = {}  # body -> transform body frame -> its link's frame
    joints: list[JointSpec] = []
    frame_name: dict[int, str] = {}  # body -> name of the link carrying its frame (after its joints)
    for b in range(1, m.nbody):
        parent = int(m.body_parentid[b])
        pname = frame_name.get(parent, nm(mujoco.mjtObj.mjOBJ_BODY, parent))
        origin = correction.get(parent, np.eye(4)) @ _T(m.body_pos[b], m.body_quat[b])
        bname = nm(mujoco.mjtObj.mjOBJ_BODY, b)
        nj = int(m.body_jntnum[b])
        if nj == 0:
            joints.append(JointSpec(f"{bname}_fixed", "fixed", pname, bname, origin, np.zeros(3)))
            frame_name[b] = bname
            continue
        prev = pname
        total = np.eye(4)
        for k in range(nj):
            j = int(m.body_jntadr[b]) + k
            jtype = int(m.jnt_type[j])
            if jtype not in (mujoco.mjtJoint.mjJNT_HINGE, mujoco.mjtJoint.mjJNT_SLIDE):
                raise HandLoadError(f"MJCF body {bname!r}: only hinge/slide joints are supported")
            hinge = jtype == mujoco.mjtJoint.mjJNT_HINGE
            child = bname if k == nj - 1 and not body_frames else f"{bname}__j{k}"
            links.setdefault(child, [])
            shift = np.eye(4)
            shift[:3, 3] = m.jnt_pos[j]
            T = np.linalg.inv(total) @ shift if k else origin @ shift
            axis = np.asarray(m.jnt_axis[j], dtype=np.float64)
            T = T @ _at_ref(axis, float(m.qpos0[int(m.jnt_qposadr[j])]), hinge)
            total = shift
            lo, hi = (float(v) for v in m.jnt_range[j]) if m.jnt_limited[j] else (-np.pi, np.pi)
            joints.append(
                JointSpec(
                    nm(mujoco.mjtObj.mjOBJ_JOINT, j), "revolute" if hinge else "prismatic", prev, child, T, axis, lo, hi
                )
            )
            prev = child
        if body_frames:  # the body's own frame, rigidly below its last joint's
            joints.append(JointSpec(f"{bname}_frame", "fixed", prev, bname, np.linalg.inv(total), np.zeros(3)))
        else:
            correction[b] = np.linalg.inv(total)
        frame_name[b] = bname
    for g in range(m.ngeom):
        if not (m.geom_contype[g] or m.geom_conaffinity[g]):
            continue
        b = int(m.geom_bodyid[g])
        if b == 0:
            continue
        mesh = _geom_mesh(m, g)
        if mesh is None:
            continue
        mesh.apply_transform(correction.get(b, np.eye(4)) @ _T(m.geom_pos[g], m.geom_quat[g]))
        links[nm(mujoco.mjtObj.mjOBJ_BODY, b)].append(mesh)
    couplings = _couplings(m, joints)
    return RobotDescription(name, nm(mujoco.mjtObj.mjOBJ_BODY, 0), links, joints, couplings)


def _at_ref(axis: np.ndarray, ref: float, hinge: bool) -> np.ndarray:
    """The motion that undoes a joint's reference value: at q = ref the child sits where the file draws it."""
    T = np.eye(4)
    if ref == 0.0:
        return T
    if hinge:
        a = axis / np.linalg.norm(axis)
        K = np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])
        T[:3, :3] = np.eye(3) + np.sin(-ref) * K + (1 - np.cos(-ref)) * K @ K
    else:
        T[:3, 3] = -ref * axis
    return T


def _geom_mesh(m: mujoco.MjModel, g: int) -> trimesh.Trimesh | None:
    import mujoco

    t, s = int(m.geom_type[g]), np.asarray(m.geom_size[g], dtype=np.float64)
    G = mujoco.mjtGeom
    if t == G.mjGEOM_BOX:
        return primitive_mesh("box", 2 * s)
    if t == G.mjGEOM_SPHERE:
        return primitive_mesh("sphere", s[:1])
    if t == G.mjGEOM_CAPSULE:
        return primitive_mesh("capsule", np.array([s[0], 2 * s[1]]))
    if t == G.mjGEOM_CYLINDER:
        return primitive_mesh("cylinder", np.array([s[0], 2 * s[1]]))
    if t == G.mjGEOM_MESH:
        mid = int(m.geom_dataid[g])
        va, vn = int(m.mesh_vertadr[mid]), int(m.mesh_vertnum[mid])
        fa, fn = int(m.mesh_faceadr[mid]), int(m.mesh_facenum[mid])
        return trimesh.Trimesh(m.mesh_vert[va : va + vn].copy(), m.mesh_face[fa : fa + fn].copy(), process=False)
    return None


def _couplings(m: mujoco.MjModel, joints: list[JointSpec]) -> list[str]:
    """Tie coupled joints as mimic joints; returns one line per coupling, honoured or left free.

    Honoured: a fixed tendon over two joints with a range of at most ``COUPLING_RANGE`` (c0·a + c1·b ≈ 0 gives
    a = −c1/c0 · b) and an active joint equality ``a = p0 + p1·b`` (about the joints' reference values). Left free
    (reported): a joint equality with higher polynomial terms, tendon equalities and other tendons.
    """
    import mujoco

    by_name = {j.name: j for j in joints}
    notes: list[str] = []

    def jname(i: int) -> str:
        return mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_JOINT, i) or f"joint_{i}"

    for t in range(m.ntendon):
        adr, num = int(m.tendon_adr[t]), int(m.tendon_num[t])
        tname = mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_TENDON, t) or f"tendon_{t}"
        lo, hi = m.tendon_range[t]
        joint_only = all(int(m.wrap_type[adr + k]) == mujoco.mjtWrap.mjWRAP_JOINT for k in range(num))
        if num != 2 or not joint_only or not m.tendon_limited[t] or max(abs(lo), abs(hi)) > COUPLING_RANGE:
            continue  # an actuated or spatial tendon couples nothing kinematically
        (ja, ca), (jb, cb) = ((int(m.wrap_objid[adr + k]), float(m.wrap_prm[adr + k])) for k in range(2))
        a, b = by_name.get(jname(ja)), by_name.get(jname(jb))
        if a is not None and b is not None and ca != 0:
            a.mimic = (b.name, -cb / ca, 0.0)
            notes.append(f"tendon {tname!r}: {a.name} = {-cb / ca:.6g} * {b.name} (honoured)")
    for e in range(m.neq):
        ename = mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_EQUALITY, e) or f"equality_{e}"
        kind = int(m.eq_type[e])
        if kind == mujoco.mjtEq.mjEQ_JOINT and int(m.eq_obj2id[e]) >= 0:
            a, b = by_name.get(jname(int(m.eq_obj1id[e]))), by_name.get(jname(int(m.eq_obj2id[e])))
            poly = np.asarray(m.eq_data[e][:5], dtype=np.float64)
            if a is None or b is None:
                continue
            if np.any(np.abs(poly[2:]) > 1e-12) or not m.eq_active0[e]:
                notes.append(f"equality {ename!r}: {a.name} ~ {b.name} is nonlinear or inactive: both left free")
                continue
            ra = float(m.qpos0[int(m.jnt_qposadr[int(m.eq_obj1id[e])])])
            rb = float(m.qpos0[int(m.jnt_qposadr[int(m.eq_obj2id[e])])])
            a.mimic = (b.name, float(poly[1]), ra + float(poly[0]) - float(poly[1]) * rb)
            notes.append(f"equality {ename!r}: {a.name} = {poly[1]:.6g} * {b.name} + {a.mimic[2]:.6g} (honoured)")
        elif kind in (mujoco.mjtEq.mjEQ_CONNECT, mujoco.mjtEq.mjEQ_WELD, mujoco.mjtEq.mjEQ_TENDON):
            what = {mujoco.mjtEq.mjEQ_CONNECT: "connect", mujoco.mjtEq.mjEQ_WELD: "weld"}.get(kind, "tendon")
            obj = mujoco.mjtObj.mjOBJ_TENDON if kind == mujoco.mjtEq.mjEQ_TENDON else mujoco.mjtObj.mjOBJ_BODY
            ends = [mujoco.mj_id2name(m, obj, int(i)) or "" for i in (m.eq_obj1id[e], m.eq_obj2id[e]) if i >= 0]
            notes.append(
                f"equality {ename!r} ({what} {' '.join(ends)}): a closed loop or tendon coupling, not modelled: "
                "its joints are free"
            )
    return notes
