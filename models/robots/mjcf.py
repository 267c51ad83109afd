"""MJCF (MuJoCo) descriptions for built-in hands that ship only as MJCF (Shadow).

The file is compiled by ``mujoco`` itself (defaults, classes, includes, mesh assets), then its body tree is read
back into a :class:`RobotDescription`: one link per body, hinge → revolute, slide → prismatic, geoms with
``contype | conaffinity`` ≠ 0 as collision meshes. A fixed tendon over two joints with a range of at most
``COUPLING_RANGE`` (Shadow's ``T_xxJ1c``: c0·J0 + c1·J1 ≈ 0) ties its first joint to its second
(J0 = −c1/c0 · J1): we treat it as an exact mimic joint.

Only for trusted, packaged files: ``mujoco`` opens the meshes the MJCF names.
"""

from __future__ import annotations

import numpy as np
import trimesh

from models.robots.description import HandLoadError, JointSpec, RobotDescription, primitive_mesh

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

    m = mujoco.MjModel.from_xml_path(path)

    def nm(obj: mujoco.mjtObj, i: int) -> str:
        return mujoco.mj_id2name(m, obj, i) or f"{obj.name}_{i}"

    links: dict[str, list[trimesh.Trimesh]] = {nm(mujoco.mjtObj.mjOBJ_BODY, b): [] for b in range(m.nbody)}
    correction: dict[int, np.ndarray] = {}  # body -> transform body frame -> last joint frame
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
            child = bname if k == nj - 1 else f"{bname}__j{k}"
            links.setdefault(child, [])
            shift = np.eye(4)
            shift[:3, 3] = m.jnt_pos[j]
            T = (origin if k == 0 else np.eye(4)) @ np.linalg.inv(total) @ shift if k else origin @ shift
            total = shift
            lo, hi = (float(v) for v in m.jnt_range[j]) if m.jnt_limited[j] else (-np.pi, np.pi)
            joints.append(
                JointSpec(
                    nm(mujoco.mjtObj.mjOBJ_JOINT, j),
                    "revolute" if jtype == mujoco.mjtJoint.mjJNT_HINGE else "prismatic",
                    prev,
                    child,
                    T,
                    np.asarray(m.jnt_axis[j], dtype=np.float64),
                    lo,
                    hi,
                )
            )
            prev = child
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
    _couplings(m, joints)
    return RobotDescription(name, nm(mujoco.mjtObj.mjOBJ_BODY, 0), links, joints)


def _geom_mesh(m, g: int) -> trimesh.Trimesh | None:
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


def _couplings(m, joints: list[JointSpec]) -> None:
    import mujoco

    by_name = {j.name: j for j in joints}
    for t in range(m.ntendon):
        adr, num = int(m.tendon_adr[t]), int(m.tendon_num[t])
        lo, hi = m.tendon_range[t]
        if num != 2 or not m.tendon_limited[t] or max(abs(lo), abs(hi)) > COUPLING_RANGE:
            continue
        if any(int(m.wrap_type[adr + k]) != mujoco.mjtWrap.mjWRAP_JOINT for k in range(2)):
            continue
        (ja, ca), (jb, cb) = ((int(m.wrap_objid[adr + k]), float(m.wrap_prm[adr + k])) for k in range(2))
        a = by_name.get(mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_JOINT, ja) or "")
        b = by_name.get(mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_JOINT, jb) or "")
        if a is not None and b is not None and ca != 0:
            a.mimic = (b.name, -cb / ca, 0.0)
