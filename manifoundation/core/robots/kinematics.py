"""Batched forward kinematics and point Jacobians of a hand with a floating palm.

Fixed joints are collapsed: a *body* is the palm (root) or the child link of a moving joint; every other link is
rigidly attached to a body with a constant transform. Mimic/coupled joints become a free joint times a multiplier
plus an offset, so the free joint vector q (D,) drives all moving joints.

Jacobian columns (6 + D): 0:3 palm translation (world), 3:6 a small world-frame rotation ω about the palm origin
(a point p moves by ω × (p − palm_pos)), 6: the free finger joints.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import torch

from manifoundation.core.errors import HandLoadError
from manifoundation.core.robots.description import JointSpec, RobotDescription
from manifoundation.core.robots.kinematics_kernels import body_poses_one, point_jacobian_one

FIXED, REVOLUTE, PRISMATIC = 0, 1, 2


def skew_np(v: np.ndarray) -> np.ndarray:
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def quat_to_matrix(quat: torch.Tensor) -> torch.Tensor:
    """(B, 4) wxyz (normalised here) -> (B, 3, 3)."""
    q = quat / quat.norm(dim=-1, keepdim=True)
    w, x, y, z = q.unbind(-1)
    return torch.stack(
        [
            1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y),
            2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x),
            2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y),
        ],
        dim=-1,
    ).reshape(*quat.shape[:-1], 3, 3)  # fmt: skip


def quat_multiply(a: torch.Tensor, b: torch.Tensor) -> torch.Tensor:
    """Hamilton product a ⊗ b of (..., 4) wxyz quaternions."""
    aw, ax, ay, az = a.unbind(-1)
    bw, bx, by, bz = b.unbind(-1)
    return torch.stack(
        [
            aw * bw - ax * bx - ay * by - az * bz,
            aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw,
        ],
        dim=-1,
    )


def quat_exp(omega: torch.Tensor) -> torch.Tensor:
    """Rotation vector (..., 3) -> unit quaternion (..., 4) wxyz (exact, smooth at 0)."""
    angle = omega.norm(dim=-1, keepdim=True)
    half = 0.5 * angle
    # sin(half)/angle with its Taylor series near 0
    small = angle < 1e-8
    k = torch.where(small, 0.5 - angle * angle / 48.0, torch.sin(half) / torch.where(small, 1.0, angle))
    return torch.cat([torch.cos(half), omega * k], dim=-1)


def one_cpu_pose(*tensors: torch.Tensor) -> bool:
    """Whether the compiled path applies: a batch of one, float64 on the CPU, no gradient asked."""
    return all(
        t.shape[0] == 1 and t.dtype == torch.float64 and t.device.type == "cpu" and not t.requires_grad
        for t in tensors
    )


def one_pose_values(t: torch.Tensor) -> np.ndarray:
    """The tensor's values as a contiguous float64 array, without its batch axis of one."""
    return np.ascontiguousarray(t[0].numpy())


@dataclass
class _Consts:
    origin: torch.Tensor  # (nb, 4, 4)
    K: torch.Tensor  # (nb, 3, 3) skew(axis)
    K2: torch.Tensor  # (nb, 3, 3)
    axis: torch.Tensor  # (nb, 3)
    rev: torch.Tensor  # (nb,)
    pris: torch.Tensor  # (nb,)
    mult: torch.Tensor  # (nb,)
    offset: torch.Tensor  # (nb,)
    coupling: torch.Tensor  # (nb, D): d theta_b / d q_d
    body_weights: torch.Tensor  # (nb, nb, D): [j, k, d] = d theta_k / d q_d if k is j or an ancestor of j


class KinematicTree:
    """The moving-body tree of a :class:`RobotDescription` rooted at the palm link.

    Attributes:
        body_names: (nb,) body link names, body 0 = palm, parents before children.
        parent: (nb,) parent body index (-1 for the palm).
        link_body: link name -> (body index, (4, 4) transform body -> link).
        joint_names: (D,) free joints; lower/upper (D,) their limits (tightened so tied joints stay in range).
        ancestors: (nb, nb) bool, ancestors[b, a] = a is b or an ancestor of b.
    """

    def __init__(self, desc: RobotDescription, palm: str | None = None) -> None:
        desc = desc.subtree(palm) if palm is not None and palm != desc.root else desc
        children: dict[str, list[JointSpec]] = {}
        for j in desc.joints:
            children.setdefault(j.parent, []).append(j)
        self.body_names: list[str] = [desc.root]
        self.link_body: dict[str, tuple[int, np.ndarray]] = {desc.root: (0, np.eye(4))}
        parent: list[int] = [-1]
        origins: list[np.ndarray] = [np.eye(4)]
        axes: list[np.ndarray] = [np.zeros(3)]
        kinds: list[int] = [FIXED]
        moving: list[JointSpec | None] = [None]
        stack = list(children.get(desc.root, []))
        while stack:  # depth-first in document order: a body's index follows its parent's
            j = stack.pop(0)
            body, T_bl = self.link_body[j.parent]
            if j.type == "fixed":
                self.link_body[j.child] = (body, T_bl @ j.origin)
            else:
                self.body_names.append(j.child)
                self.link_body[j.child] = (len(self.body_names) - 1, np.eye(4))
                parent.append(body)
                origins.append(T_bl @ j.origin)
                axes.append(j.axis)
                kinds.append(PRISMATIC if j.type == "prismatic" else REVOLUTE)
                moving.append(j)
            stack[0:0] = children.get(j.child, [])
        self.parent = np.asarray(parent)
        free = [j for j in moving if j is not None and j.mimic is None]
        self.joint_names = [j.name for j in free]
        index = {n: i for i, n in enumerate(self.joint_names)}
        lower = np.array([j.lower for j in free], dtype=np.float64)
        upper = np.array([j.upper for j in free], dtype=np.float64)
        nb, D = len(self.body_names), len(free)
        coupling = np.zeros((nb, D))
        offset = np.zeros(nb)
        mult = np.zeros(nb)
        for b, mj in enumerate(moving):
            if mj is None:
                continue
            src, m, off = mj.mimic if mj.mimic is not None else (mj.name, 1.0, 0.0)
            if src not in index:
                raise HandLoadError(f"joint {mj.name!r}: mimic source {src!r} is not a joint of this hand")
            d = index[src]
            coupling[b, d], mult[b], offset[b] = m, m, off
            if mj.mimic is not None and abs(m) > 1e-12:  # keep the tied joint inside its own limits
                lo, hi = sorted(((mj.lower - off) / m, (mj.upper - off) / m))
                lower[d], upper[d] = max(lower[d], lo), min(upper[d], hi)
        if np.any(lower > upper):
            raise HandLoadError("mimic joints leave an empty range for their source joint")
        self.lower, self.upper = lower, upper
        self._src = np.array([int(np.argmax(np.abs(coupling[b]))) if mult[b] != 0 else 0 for b in range(nb)])
        anc = np.zeros((nb, nb), dtype=bool)
        for b in range(nb):
            a = b
            while a >= 0:
                anc[b, a] = True
                a = int(self.parent[a])
        self.ancestors = anc
        depth = anc.sum(1) - 1
        self._levels = [np.nonzero(depth == d)[0] for d in range(1, int(depth.max()) + 1)] if nb > 1 else []
        kinds_a = np.asarray(kinds)
        origin_a = np.stack(origins)
        # flush round-off (e.g. 1e-76 from CAD exports): products of such values go subnormal and slow FK down 3x
        origin_a[np.abs(origin_a) < 1e-14] = 0.0
        for link, (bb, T) in self.link_body.items():
            T = T.copy()
            T[np.abs(T) < 1e-14] = 0.0
            self.link_body[link] = (bb, T)
        self._np = {
            "origin": origin_a,
            "K": np.stack([skew_np(a) for a in axes]),
            "axis": np.stack(axes),
            "rev": (kinds_a == REVOLUTE).astype(np.float64),
            "pris": (kinds_a == PRISMATIC).astype(np.float64),
            "mult": mult,
            "offset": offset,
            "coupling": coupling,
            "body_weights": anc[:, :, None] * coupling[None],
        }
        self._cache: dict[tuple[torch.dtype, torch.device], _Consts] = {}
        self._level_cache: dict[torch.device, list[tuple[torch.Tensor, torch.Tensor]]] = {}
        self._src_t: dict[torch.device, torch.Tensor] = {}

    @property
    def dof(self) -> int:
        return len(self.joint_names)

    def consts(self, dtype: torch.dtype, device: torch.device) -> _Consts:
        key = (dtype, device)
        if key not in self._cache:
            t = {k: torch.as_tensor(v, dtype=dtype, device=device) for k, v in self._np.items()}
            self._cache[key] = _Consts(
                t["origin"], t["K"], t["K"] @ t["K"], t["axis"], t["rev"], t["pris"], t["mult"], t["offset"],
                t["coupling"], t["body_weights"],
            )  # fmt: skip
        return self._cache[key]

    def body_poses(self, palm_pos: torch.Tensor, palm_quat: torch.Tensor, q: torch.Tensor) -> torch.Tensor:
        """World poses of every body: (B, 3), (B, 4) wxyz, (B, D) -> (B, nb, 4, 4)."""
        if one_cpu_pose(q, palm_pos, palm_quat):
            k = self._np
            at = one_pose_values
            return torch.from_numpy(body_poses_one(
                at(palm_pos), at(palm_quat), at(q), self._src, k["mult"], k["offset"], k["rev"], k["pris"], k["axis"],
                k["origin"], self.parent,
            ))[None]  # fmt: skip
        c = self.consts(q.dtype, q.device)
        B, nb = q.shape[0], len(self.body_names)
        src = self._src_t.get(q.device)
        if src is None:
            src = self._src_t[q.device] = torch.as_tensor(self._src, device=q.device)
        theta = q[:, src] * c.mult + c.offset if self.dof else c.offset.expand(B, nb)  # (B, nb)
        s = (torch.sin(theta) * c.rev)[..., None, None]
        cm = ((1 - torch.cos(theta)) * c.rev)[..., None, None]
        eye3 = torch.eye(3, dtype=q.dtype, device=q.device)
        R = eye3 + s * c.K + cm * c.K2  # (B, nb, 3, 3)
        t = (theta * c.pris)[..., None] * c.axis  # (B, nb, 3)
        local = torch.empty(B, nb, 4, 4, dtype=q.dtype, device=q.device)
        local[..., :3, :3] = c.origin[:, :3, :3] @ R
        local[..., :3, 3] = c.origin[:, :3, 3] + (c.origin[:, :3, :3] @ t[..., None])[..., 0]
        local[..., 3, :3] = 0
        local[..., 3, 3] = 1
        palm = torch.zeros(B, 4, 4, dtype=q.dtype, device=q.device)
        palm[:, :3, :3] = quat_to_matrix(palm_quat)
        palm[:, :3, 3] = palm_pos
        palm[:, 3, 3] = 1
        out = [palm] + [palm] * (nb - 1)
        T = torch.stack(out, dim=1).clone() if nb > 1 else palm[:, None].clone()
        for idx_t, par_t in self._level_index(q.device):
            T[:, idx_t] = T[:, par_t] @ local[:, idx_t]
        return T

    def _level_index(self, device: torch.device) -> list[tuple[torch.Tensor, torch.Tensor]]:
        if device not in self._level_cache:
            self._level_cache[device] = [
                (torch.as_tensor(idx, device=device), torch.as_tensor(self.parent[idx], device=device))
                for idx in self._levels
            ]
        return self._level_cache[device]

    def point_jacobian(
        self, T: torch.Tensor, bodies: np.ndarray, points: torch.Tensor, palm_pos: torch.Tensor
    ) -> torch.Tensor:
        """Jacobian (B, n, 3, 6 + D) of world points (B, n, 3) rigidly attached to ``bodies`` (n,).

        Per body j, the joint columns of a point p on j are Σ_k W[j,k,d] (a_k × (p − o_k)) for revolute and
        Σ_k W[j,k,d] a_k for prismatic ancestors k (world axis a_k through o_k, W the coupling-weighted ancestor
        table): = A_j × p − C_j with A_j, C_j per body, so the cost grows with bodies, not points.
        """
        if one_cpu_pose(T, points, palm_pos):
            k = self._np
            return torch.from_numpy(point_jacobian_one(
                one_pose_values(T), np.asarray(bodies, dtype=np.int64), one_pose_values(points).reshape(-1, 3),
                one_pose_values(palm_pos), k["axis"], k["rev"], k["pris"], k["body_weights"],
            ))[None]  # fmt: skip
        c = self.consts(points.dtype, points.device)
        B, n = points.shape[:2]
        D = self.dof
        J = points.new_zeros(B, n, 3, 6 + D)
        J[..., 0, 0] = J[..., 1, 1] = J[..., 2, 2] = 1.0
        rp = points - palm_pos[:, None]
        # ω × rp = -[rp]x ω
        J[..., 0, 4], J[..., 0, 5] = rp[..., 2], -rp[..., 1]
        J[..., 1, 3], J[..., 1, 5] = -rp[..., 2], rp[..., 0]
        J[..., 2, 3], J[..., 2, 4] = rp[..., 1], -rp[..., 0]
        if D:
            axis_w = (T[..., :3, :3] @ c.axis[..., None])[..., 0]  # (B, nb, 3)
            o_w = T[..., :3, 3]
            rev, pris = c.rev[:, None], c.pris[:, None]
            nb = axis_w.shape[1]
            # Σ_k W[j,k,d] x_k as one matrix product ((nb·D, nb) @ (B, nb, 3)): einsum took 2.5 ms a call here
            W = c.body_weights.permute(0, 2, 1).reshape(nb * D, nb)
            A = (W @ (axis_w * rev)).reshape(B, nb, D, 3)
            C = (W @ (torch.linalg.cross(axis_w, o_w, dim=-1) * rev - axis_w * pris)).reshape(B, nb, D, 3)
            idx = torch.as_tensor(bodies, device=points.device)
            Ap, Cp = A[:, idx], C[:, idx]  # (B, n, D, 3)
            Jq = torch.linalg.cross(Ap, points[:, :, None, :].expand_as(Ap), dim=-1) - Cp
            J[..., 6:] = Jq.transpose(-1, -2)
        return J
