"""`Hand`: a robot hand with a floating 6-DoF palm in front of its finger joints.

Conventions (shared with refinement and verification):

- palm pose: position (B, 3) and quaternion (B, 4) wxyz, world frame; finger joints q (B, D) free joints (mimic /
  coupled joints tied to them).
- Jacobian columns (6 + D): 0:3 palm translation (world), 3:6 a small world-frame rotation ω about the palm origin
  (a point p moves by ω × (p − palm_pos)), 6: the finger joints; :meth:`Hand.apply_delta` applies exactly that
  step (palm_pos += δt, palm_quat = quat(exp(δω)) ⊗ palm_quat, q += δq, no clamping).
- All methods take torch tensors, batch first; dtype and device follow the inputs (float64 supported).

Why one module: `Hand` is one class, its kinematics, geometry and Jacobians; splitting it would scatter one object's
invariants.
"""

from __future__ import annotations

from functools import cached_property
from typing import cast

import numpy as np
import torch
import trimesh

from manifoundation.core.errors import HandLoadError
from manifoundation.core.robots.description import RobotDescription
from manifoundation.core.robots.kinematics import KinematicTree, one_cpu_pose, one_pose_values, quat_exp, quat_multiply
from manifoundation.core.robots.kinematics_kernels import apply_delta_one, on_bodies_one
from manifoundation.core.robots.pads import ContactSurface, build_contact_surface
from manifoundation.core.robots.spheres import fit_spheres, sample_surface

SURFACE_POINTS = 1024
ADJACENT_HOPS = 2
"""Body pairs at most this many tree edges apart along one branch are never checked for self-collision."""


class Hand:
    """Kinematics, collision spheres and geometry of one hand (see module doc for conventions).

    Built-ins are shared per process (:func:`manifoundation.core.robots.get_hand` caches them): treat every attribute as
    read-only (copy ``rest`` before editing it).

    Attributes:
        name: registry name.
        joint_names: (D,) free finger joints; lower, upper, rest: (D,) float64.
        fingertip_links: (m,) link names; tip_offsets: (m, 3) contact points in those link frames.
        approach_axis: (3,) unit, palm frame: the direction the palm faces / the fingers close towards.
        sphere_links: (S,) body link names; sphere_centres (S, 3) in those link frames; sphere_radii (S,).
        sphere_fingertip: (S,) index of the fingertip whose link body carries the sphere, else -1.
        self_collision_pairs: (P, 2) sphere index pairs that must not overlap.
        surface_points, surface_normals: (1024, 3) palm frame, rest pose, outward unit normals.
        collision_meshes: body link name -> mesh in that link's frame (fixed children merged in).
    """

    def __init__(
        self,
        desc: RobotDescription,
        *,
        name: str,
        fingertips: list[str],
        tip_offsets: np.ndarray | None = None,
        palm: str | None = None,
        rest: np.ndarray | dict[str, float] | None = None,
        approach_axis: np.ndarray | list[float] | None = None,
    ) -> None:
        self.name = name
        self.description = desc
        """The description the hand was built from (links with their collision meshes; physics builds from it)."""
        self.tree = tree = KinematicTree(desc, palm)
        self.joint_names = list(tree.joint_names)
        self.lower, self.upper = tree.lower.copy(), tree.upper.copy()
        if not np.all(np.isfinite(self.lower)) or not np.all(np.isfinite(self.upper)):
            raise HandLoadError("joint limits must be finite")
        unknown = [f for f in fingertips if f not in tree.link_body]
        if not fingertips or unknown:
            raise HandLoadError(
                f"unknown fingertip links {unknown} (links below the palm: {sorted(tree.link_body)[:40]})"
                if unknown
                else "at least one fingertip link is required"
            )
        self.fingertip_links = list(fingertips)
        m = len(fingertips)
        offs = np.zeros((m, 3)) if tip_offsets is None else np.asarray(tip_offsets, dtype=np.float64)
        if offs.shape != (m, 3) or not np.all(np.isfinite(offs)):
            raise HandLoadError(f"tip_offsets must be finite with shape ({m}, 3), got {offs.shape}")
        self.tip_offsets = offs
        self.rest = self._rest(rest)
        axis = np.array([0.0, 0.0, 1.0]) if approach_axis is None else np.asarray(approach_axis, float).reshape(-1)
        if axis.shape != (3,) or not np.all(np.isfinite(axis)) or np.linalg.norm(axis) < 1e-9:
            raise HandLoadError(f"approach_axis must be a finite non-zero 3-vector, got {axis.tolist()}")
        self.approach_axis = axis / np.linalg.norm(axis)

        # geometry of each body, in the body frame
        self.collision_meshes: dict[str, trimesh.Trimesh] = {}
        per_body: dict[int, list[trimesh.Trimesh]] = {}
        for link, (b, T) in tree.link_body.items():
            for mesh in desc.links.get(link, []):
                mm = mesh.copy()
                mm.apply_transform(T)
                per_body.setdefault(b, []).append(mm)
        for b, meshes in sorted(per_body.items()):
            self.collision_meshes[tree.body_names[b]] = cast(trimesh.Trimesh, trimesh.util.concatenate(meshes))
        if not self.collision_meshes:
            raise HandLoadError("the hand has no collision geometry (user URDFs need box/sphere/cylinder shapes)")
        # each fingertip body's links with geometry, in the body frame: a contact names the link it lies on
        self._tip_link_meshes: list[dict[str, trimesh.Trimesh]] = []
        for link in self.fingertip_links:
            b, _ = tree.link_body[link]
            parts: dict[str, trimesh.Trimesh] = {}
            for name, (bb, T) in tree.link_body.items():
                own = [m.copy().apply_transform(T) for m in desc.links.get(name, [])] if bb == b else []
                if own:
                    parts[name] = cast(trimesh.Trimesh, trimesh.util.concatenate(own))
            self._tip_link_meshes.append(parts)
        # fingertip points in their bodies
        tip_body, tip_local = [], []
        for link, off in zip(self.fingertip_links, self.tip_offsets, strict=True):
            b, T = tree.link_body[link]
            tip_body.append(b)
            tip_local.append(T[:3, :3] @ off + T[:3, 3])
        self._tip_body = np.asarray(tip_body, dtype=np.int64)
        self._tip_local = np.asarray(tip_local)
        self._cache: dict[tuple[str, torch.dtype, torch.device], torch.Tensor] = {}
        self._fit_spheres()

    # ------------------------------------------------------------------ construction helpers
    def _rest(self, rest: np.ndarray | dict[str, float] | None) -> np.ndarray:
        D = len(self.joint_names)
        if rest is None:
            r = np.zeros(D)
        elif isinstance(rest, dict):
            r = np.zeros(D)
            for k, v in rest.items():
                if k not in self.joint_names:
                    raise HandLoadError(f"rest: {k!r} is not a free joint ({self.joint_names})")
                r[self.joint_names.index(k)] = v
        else:
            r = np.asarray(rest, dtype=np.float64).reshape(-1)
            if r.shape != (D,):
                raise HandLoadError(f"rest must have {D} values, got {r.shape[0]}")
        if not np.all(np.isfinite(r)):
            raise HandLoadError("rest values must be finite")
        return np.clip(r, self.lower, self.upper)

    def _fit_spheres(self) -> None:
        tree = self.tree
        links, centres, radii, bodies = [], [], [], []
        for link, mesh in self.collision_meshes.items():
            c, r = fit_spheres(mesh)
            b = tree.body_names.index(link)
            links += [link] * len(r)
            centres.append(c)
            radii.append(r)
            bodies += [b] * len(r)
        self.sphere_links: list[str] = links
        self.sphere_centres = np.vstack(centres) if centres else np.zeros((0, 3))
        self.sphere_radii = np.concatenate(radii) if radii else np.zeros(0)
        self._sphere_body = np.asarray(bodies, dtype=np.int64)
        self.sphere_fingertip = np.full(len(links), -1, dtype=np.int64)
        for i, b in enumerate(self._tip_body):
            self.sphere_fingertip[self._sphere_body == b] = i
        self.self_collision_pairs = self._pairs()

    def _pairs(self) -> np.ndarray:
        """Sphere pairs on bodies more than ADJACENT_HOPS apart (or on different branches) that do not already
        overlap at the rest pose."""
        n = len(self.sphere_radii)
        if n < 2:
            return np.zeros((0, 2), dtype=np.int64)
        depth = self.tree.ancestors.sum(1)
        ab = self._sphere_body
        anc = self.tree.ancestors
        i, j = np.triu_indices(n, 1)
        bi, bj = ab[i], ab[j]
        related = anc[bi, bj] | anc[bj, bi]
        close = related & (np.abs(depth[bi] - depth[bj]) <= ADJACENT_HOPS)
        dtype = torch.float64
        pos, quat = torch.zeros(1, 3, dtype=dtype), torch.tensor([[1.0, 0, 0, 0]], dtype=dtype)
        ct, _ = self.spheres(pos, quat, torch.as_tensor(self.rest[None]), jacobian=False)
        c = ct[0].numpy()
        overlap = np.linalg.norm(c[i] - c[j], axis=1) < self.sphere_radii[i] + self.sphere_radii[j]
        keep = (bi != bj) & ~close & ~overlap
        return np.stack([i[keep], j[keep]], axis=1).astype(np.int64)

    @cached_property
    def _surface(self) -> tuple[np.ndarray, np.ndarray]:
        dtype = torch.float64
        pos, quat = torch.zeros(1, 3, dtype=dtype), torch.tensor([[1.0, 0, 0, 0]], dtype=dtype)
        poses = self.link_poses(pos, quat, torch.as_tensor(self.rest[None]))
        meshes = []
        for link, mesh in self.collision_meshes.items():
            mm = mesh.copy()
            mm.apply_transform(poses[link][0].numpy())
            meshes.append(mm)
        return sample_surface(meshes, SURFACE_POINTS)

    @cached_property
    def contact_surface(self) -> ContactSurface:
        """Samples of the fingertip bodies' real meshes: contact candidates (pads) and their guards
        (`manifoundation.core.robots.pads`)."""
        meshes = {self.tree.body_names.index(name): mesh for name, mesh in self.collision_meshes.items()}
        return build_contact_surface(meshes, self._tip_body, self._tip_local, link_meshes=self._tip_link_meshes)

    @cached_property
    def fingertip_parts(self) -> list[list[tuple[np.ndarray, np.ndarray]]]:
        """Per fingertip, the convex parts of its body's mesh: half-spaces (f, 4) ``n·x ≤ d`` of each connected
        part's hull and its bounds (2, 3), body frame (object points inside them are penetrations)."""
        from manifoundation.core.robots.pads import convex_parts

        return [convex_parts(self.collision_meshes[b]) for b in self.fingertip_bodies]

    @property
    def fingertip_bodies(self) -> list[str]:
        """(m,) the body (link with fixed children merged) of each fingertip, keys of ``collision_meshes``."""
        return [self.tree.body_names[b] for b in self._tip_body]

    @property
    def fingertip_body_index(self) -> np.ndarray:
        """(m,) index (into ``tree.body_names``) of each fingertip's body."""
        return self._tip_body

    def surface_samples(
        self, palm_pos: torch.Tensor, palm_quat: torch.Tensor, q: torch.Tensor, index: np.ndarray | None = None,
        jacobian: bool = True, body_poses: torch.Tensor | None = None,
    ) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor | None]:  # fmt: skip
        """World positions (B, k, 3), outward normals (B, k, 3) and Jacobians (B, k, 3, 6 + D) (None without
        ``jacobian``) of the contact-surface samples ``index`` (default: all K). ``body_poses``: the
        ``tree.body_poses`` of this pose when the caller has them already."""
        self._check(palm_pos, palm_quat, q)
        surf = self.contact_surface
        T = self.tree.body_poses(palm_pos, palm_quat, q) if body_poses is None else body_poses
        if index is None:  # every sample (the contact model's every iterate): the constant tensors made once
            bodies = surf.body
            body_index = self._const("surface_body", q)
            local, nrm = self._const("surface_local", q), self._const("surface_normals", q)
        else:
            idx = np.asarray(index, dtype=np.int64)
            bodies = surf.body[idx]
            body_index = torch.as_tensor(bodies, device=q.device)
            local = torch.as_tensor(surf.local[idx], dtype=q.dtype, device=q.device)
            nrm = torch.as_tensor(surf.normals[idx], dtype=q.dtype, device=q.device)
        if one_cpu_pose(T, q):  # the constants below are made like q
            at, where = one_pose_values(T), np.asarray(bodies, dtype=np.int64)
            pts = torch.from_numpy(on_bodies_one(at, where, local.numpy(), True))[None]
            normals = torch.from_numpy(on_bodies_one(at, where, nrm.numpy(), False))[None]
        else:
            Tb = T[:, body_index]
            pts = (Tb[..., :3, :3] @ local[..., None])[..., 0] + Tb[..., :3, 3]
            normals = (Tb[..., :3, :3] @ nrm[..., None])[..., 0]
        if not jacobian:
            return pts, normals, None
        return pts, normals, self.tree.point_jacobian(T, bodies, pts, palm_pos)

    @property
    def surface_points(self) -> np.ndarray:
        return self._surface[0]

    @property
    def surface_normals(self) -> np.ndarray:
        return self._surface[1]

    # ------------------------------------------------------------------ sizes
    @property
    def dof(self) -> int:
        return len(self.joint_names)

    @property
    def num_fingertips(self) -> int:
        return len(self.fingertip_links)

    def __repr__(self) -> str:
        return (
            f"Hand({self.name!r}, dof={self.dof}, fingertips={self.num_fingertips}, spheres={len(self.sphere_radii)})"
        )

    # ------------------------------------------------------------------ kinematics
    def _const(self, key: str, like: torch.Tensor) -> torch.Tensor:
        k = (key, like.dtype, like.device)
        if k not in self._cache:
            if key == "tip_local":
                v = torch.as_tensor(self._tip_local, dtype=like.dtype, device=like.device)
            elif key == "sphere_local":
                v = torch.as_tensor(self.sphere_centres, dtype=like.dtype, device=like.device)
            elif key == "surface_body":  # an index: its own integer dtype
                v = torch.as_tensor(self.contact_surface.body, device=like.device)
            elif key == "surface_local":
                v = torch.as_tensor(self.contact_surface.local, dtype=like.dtype, device=like.device)
            elif key == "surface_normals":
                v = torch.as_tensor(self.contact_surface.normals, dtype=like.dtype, device=like.device)
            else:
                raise KeyError(key)
            self._cache[k] = v
        return self._cache[k]

    def _check(self, palm_pos: torch.Tensor, palm_quat: torch.Tensor, q: torch.Tensor) -> None:
        B = palm_pos.shape[0]
        if palm_pos.shape != (B, 3) or palm_quat.shape != (B, 4) or q.shape != (B, self.dof):
            raise ValueError(
                f"expected palm_pos (B,3), palm_quat (B,4), q (B,{self.dof}); got "
                f"{tuple(palm_pos.shape)}, {tuple(palm_quat.shape)}, {tuple(q.shape)}"
            )

    def _points(
        self, palm_pos: torch.Tensor, palm_quat: torch.Tensor, q: torch.Tensor, which: str, jacobian: bool
    ) -> tuple[torch.Tensor, torch.Tensor | None]:
        self._check(palm_pos, palm_quat, q)
        T = self.tree.body_poses(palm_pos, palm_quat, q)
        bodies = self._tip_body if which == "tip" else self._sphere_body
        local = self._const("tip_local" if which == "tip" else "sphere_local", q)
        Tb = T[:, torch.as_tensor(bodies, device=q.device)]  # (B, n, 4, 4)
        pts = (Tb[..., :3, :3] @ local[..., None])[..., 0] + Tb[..., :3, 3]
        if not jacobian:
            return pts, None
        return pts, self.tree.point_jacobian(T, bodies, pts, palm_pos)

    def link_poses(self, palm_pos: torch.Tensor, palm_quat: torch.Tensor, q: torch.Tensor) -> dict[str, torch.Tensor]:
        """World pose (B, 4, 4) of every link below the palm (including fixed ones)."""
        self._check(palm_pos, palm_quat, q)
        T = self.tree.body_poses(palm_pos, palm_quat, q)
        names = list(self.tree.link_body)
        key = ("link_offsets", q.dtype, q.device)
        if key not in self._cache:
            offs = np.stack([self.tree.link_body[n][1] for n in names])
            self._cache[key] = torch.as_tensor(offs, dtype=q.dtype, device=q.device)
        bodies = torch.as_tensor([self.tree.link_body[n][0] for n in names], device=q.device)
        poses = T[:, bodies] @ self._cache[key]  # (B, L, 4, 4), one batched product
        out = {n: poses[:, i] for i, n in enumerate(names)}
        return out

    def fingertips(self, palm_pos: torch.Tensor, palm_quat: torch.Tensor, q: torch.Tensor) -> torch.Tensor:
        """World fingertip contact points (B, m, 3)."""
        return self._points(palm_pos, palm_quat, q, "tip", False)[0]

    def fingertip_jacobians(
        self, palm_pos: torch.Tensor, palm_quat: torch.Tensor, q: torch.Tensor
    ) -> tuple[torch.Tensor, torch.Tensor]:
        """Fingertip points (B, m, 3) and their Jacobians (B, m, 3, 6 + D)."""
        p, J = self._points(palm_pos, palm_quat, q, "tip", True)
        assert J is not None
        return p, J

    def spheres(
        self, palm_pos: torch.Tensor, palm_quat: torch.Tensor, q: torch.Tensor, jacobian: bool = True
    ) -> tuple[torch.Tensor, torch.Tensor]:
        """World sphere centres (B, S, 3) and their Jacobians (B, S, 3, 6 + D) (radii: ``sphere_radii``).

        With ``jacobian=False`` the second item is an empty tensor.
        """
        p, J = self._points(palm_pos, palm_quat, q, "sphere", jacobian)
        return p, (J if J is not None else p.new_zeros(0))

    def apply_delta(
        self, palm_pos: torch.Tensor, palm_quat: torch.Tensor, q: torch.Tensor, delta: torch.Tensor
    ) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
        """One step (B, 6 + D) in Jacobian-column order; returns the new (palm_pos, palm_quat, q), no clamping."""
        if one_cpu_pose(palm_pos, palm_quat, q, delta):
            at = one_pose_values
            pos, quat, joints = apply_delta_one(at(palm_pos), at(palm_quat), at(q), at(delta))
            return torch.from_numpy(pos)[None], torch.from_numpy(quat)[None], torch.from_numpy(joints)[None]
        new_quat = quat_multiply(quat_exp(delta[:, 3:6]), palm_quat)
        new_quat = new_quat / new_quat.norm(dim=-1, keepdim=True)
        return palm_pos + delta[:, :3], new_quat, q + delta[:, 6:]
