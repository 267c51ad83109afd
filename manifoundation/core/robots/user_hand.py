"""A user's hand: a URDF or MJCF (alone, or in an archive with its meshes), cut at its palm, with a report.

The procedure (every step the same for URDF and MJCF):

1. The archive is checked and read in memory (:mod:`.archive`); the description is the member named,
   else the archive's only ``.urdf``, else its only MJCF (``.xml``/``.mjcf`` with a ``<mujoco>`` root).
2. The description is parsed hardened: a URDF with :func:`.urdf.parse_urdf` (mesh files resolved in
   the archive only, geometry read only for the links below the palm), an MJCF rewritten and compiled by MuJoCo
   from memory (:mod:`.mjcf_archive`), body frames kept so palm poses mean what they mean in MuJoCo.
3. ``palm`` (default: the root link, for an MJCF the world's only body) is where the floating 6-DoF base
   attaches: the sub-tree below it is the hand, everything else is dropped (and counted in ``ignored``).
4. Fingertips default to the sub-tree's leaf links that move with a finger joint and carry geometry (one per
   body); a tip point defaults to the fingertip body's distal end: the mesh vertex farthest from the body's joint,
   pulled a quarter of the way back to the mesh's centroid (so the pad is the last 20 mm of the finger, both
   sides). The approach axis defaults to the direction from the palm origin to the fingertips' centroid at rest.
5. :class:`.hand.Hand` then generates the collision spheres, the fingertip pads and the network's
   surface point cloud from those meshes, exactly as for the built-in hands. A URDF link that collides only
   through primitives drawn around a visual mesh takes the mesh (:mod:`.real_surfaces`), as Allegro does.

Why one module: the five steps share the archive, its mesh loader and the palm's sub-tree; each step is a few
lines of this one procedure.
"""

from __future__ import annotations

import re
import time
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, cast

import numpy as np
import torch
import trimesh

from manifoundation.core.errors import HandLoadError
from manifoundation.core.robots.archive import HandArchive, read_archive
from manifoundation.core.robots.archive_meshes import ArchiveMeshes
from manifoundation.core.robots.description import RobotDescription
from manifoundation.core.robots.hand import Hand
from manifoundation.core.robots.kinematics import KinematicTree
from manifoundation.core.robots.mjcf import description_from_model
from manifoundation.core.robots.mjcf_archive import compile_mjcf
from manifoundation.core.robots.pads import PAD_RADIUS
from manifoundation.core.robots.real_surfaces import prefer_visual
from manifoundation.core.robots.urdf import parse_urdf

if TYPE_CHECKING:
    import mujoco  # no stubs: its objects read as Any

MAX_FINGERTIPS = 8
TIP_PULLBACK = 0.25


@dataclass
class HandSource:
    """What a caller sends: exactly one of ``archive`` (zip/tar bytes), ``urdf`` or ``mjcf`` (text).

    Attributes:
        name: the hand's name.
        palm: palm link/body (default: see module doc).
        fingertips: fingertip links (default: the sub-tree's leaves).
        tip_offsets: (m, 3) tip points in the fingertip link frames (default: the distal ends).
        rest: free joint → rest value (default: 0 clipped into the limits).
        approach_axis: (3,) palm-frame approach direction (default: towards the fingertips).
        description: the archive member holding the description (default: found, see module doc).
    """

    name: str
    archive: bytes | None = None
    urdf: str | None = None
    mjcf: str | None = None
    palm: str | None = None
    fingertips: list[str] | None = None
    tip_offsets: np.ndarray | None = None
    rest: dict[str, float] | None = None
    approach_axis: np.ndarray | None = None
    description: str | None = None


@dataclass
class HandBuild:
    """A built hand and what was made of the upload.

    Attributes:
        hand: the hand.
        format: ``"urdf"`` or ``"mjcf"``; description: the member or ``"inline"``.
        palm: the palm link; fingertips: (m,) fingertip links.
        pad_areas: (m,) m², the area of each fingertip pad (its body's mesh within ``PAD_RADIUS`` of the tip point).
        couplings: one line per mimic/tendon/equality coupling, honoured or left free.
        ignored: one line per thing not used, with the reason.
        meshes: number of mesh files read; seconds: build time.
    """

    hand: Hand
    format: str
    description: str
    palm: str
    fingertips: list[str]
    pad_areas: list[float]
    couplings: list[str] = field(default_factory=list)
    ignored: list[str] = field(default_factory=list)
    meshes: int = 0
    seconds: float = 0.0


def _pick_description(archive: HandArchive, wanted: str | None) -> str:
    if wanted is not None:
        if wanted not in archive.files:
            raise HandLoadError(f"description: {wanted!r} is not a member of the archive")
        return wanted
    urdfs = [n for n in archive.descriptions() if n.lower().endswith(".urdf")]
    if len(urdfs) == 1:
        return urdfs[0]
    mjcfs = [
        n for n in archive.descriptions() if not n.lower().endswith(".urdf") and b"<mujoco" in archive.files[n][:4096]
    ]
    included = {m for n in mjcfs for m in _included(archive, n)}
    found = urdfs or [n for n in mjcfs if n not in included]
    if len(found) == 1:
        return found[0]
    if not found:
        raise HandLoadError("archive: no .urdf, or .xml/.mjcf with a <mujoco> root, inside")
    raise HandLoadError(f"description: {len(found)} candidates ({', '.join(found[:6])}): name one")


def _included(archive: HandArchive, member: str) -> set[str]:
    """Members an MJCF names in ``<include file=...>`` (any that resolve; a candidate included by another is
    not the top document)."""
    base = member.rsplit("/", 1)[0] if "/" in member else ""
    out = set()
    for ref in re.findall(rb"<include\s+file\s*=\s*[\"']([^\"']{1,300})[\"']", archive.files[member]):
        try:
            out.add(archive.resolve(ref.decode(errors="replace"), base))
        except HandLoadError:
            continue
    return out


def _parse(
    src: HandSource,
) -> tuple[RobotDescription, str, str, ArchiveMeshes | None, list[str], str, dict[str, float]]:
    """(description cut at the palm, format, member, meshes, notes, palm, drawn joint values)."""
    given = [k for k in ("archive", "urdf", "mjcf") if getattr(src, k) is not None]
    if len(given) != 1:
        raise HandLoadError(f"give exactly one of archive, urdf or mjcf (got {given or 'none'})")
    if src.archive is not None:
        archive = read_archive(src.archive)
        member = _pick_description(archive, src.description)
        meshes: ArchiveMeshes | None = ArchiveMeshes(archive)
    else:
        text = src.urdf if src.urdf is not None else src.mjcf
        member = "inline.urdf" if src.urdf is not None else "inline.xml"
        archive = HandArchive({member: (text or "").encode()})
        meshes = ArchiveMeshes(archive) if src.mjcf is not None else None  # an inline URDF's meshes: ignored
    data = archive.files[member]
    notes: list[str] = []
    if b"<mujoco" in data[:4096] and b"<robot" not in data[:4096]:
        assert meshes is not None
        model, notes = compile_mjcf(archive, member, meshes)
        desc = description_from_model(model, src.name, body_frames=True)
        palm = src.palm or _only_child(desc)
        return _cut(desc, palm, notes), "mjcf", member, meshes, notes, palm, _references(model)
    skeleton = parse_urdf(data)  # structure only: which links lie below the palm
    palm = src.palm or skeleton.root
    keep = set(_cut(skeleton, palm, []).links)
    base = member.rsplit("/", 1)[0] if "/" in member else ""
    loader = meshes.loader(base) if meshes is not None else None
    surfaces = prefer_visual(data) if meshes is not None else data  # primitive covers → their real meshes
    desc = parse_urdf(surfaces, mesh_loader=loader, use_visual=meshes is not None, only_links=keep)
    if meshes is None and b"<mesh" in data:
        notes.append("urdf: mesh files of an inline URDF are not read (send an archive with the meshes)")
    return _cut(desc, palm, notes), "urdf", member, meshes, notes, palm, {}


def _references(model: mujoco.MjModel) -> dict[str, float]:
    """Joint → its MJCF ``ref`` value (the pose the file draws; the default rest pose of an MJCF hand)."""
    import mujoco

    return {
        mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, j) or f"joint_{j}": float(model.qpos0[model.jnt_qposadr[j]])
        for j in range(model.njnt)
    }


def _only_child(desc: RobotDescription) -> str:
    below = [j.child for j in desc.joints if j.parent == desc.root]
    if len(below) != 1:
        raise HandLoadError(f"palm: required (the world holds {len(below)} bodies: {below[:6]})")
    return below[0]


def _cut(desc: RobotDescription, palm: str, notes: list[str]) -> RobotDescription:
    if palm not in desc.links:
        raise HandLoadError(f"palm: {palm!r} is not a link (links: {sorted(desc.links)[:20]})")
    sub = desc.subtree(palm)
    dropped = [n for n in desc.links if n not in sub.links]
    if dropped:
        moving = sum(1 for j in desc.joints if j.child in dropped and j.type != "fixed")
        shown = ", ".join(dropped[:4]) + (" ..." if len(dropped) > 4 else "")
        notes.append(f"{len(dropped)} links and {moving} joints outside the palm's sub-tree dropped ({shown})")
    return sub


def _default_fingertips(tree: KinematicTree, desc: RobotDescription) -> list[str]:
    """One link per leaf body (a moving body with no moving child): its leaf link with geometry, else any."""
    parents = {j.parent for j in desc.joints}
    leaf_bodies = [b for b in range(1, len(tree.body_names)) if b not in set(tree.parent.tolist())]
    tips = []
    for b in leaf_bodies:
        links = [n for n, (bb, _) in tree.link_body.items() if bb == b]
        shaped = [n for n in links if desc.links.get(n)]
        leaves = [n for n in shaped if n not in parents]
        if shaped:
            tips.append((leaves or shaped)[-1])
    if not tips:
        raise HandLoadError("fingertips: the palm's sub-tree has no moving leaf link with geometry; name them")
    if len(tips) > MAX_FINGERTIPS:
        raise HandLoadError(f"fingertips: {len(tips)} leaf links ({', '.join(tips[:10])}), at most {MAX_FINGERTIPS}")
    return tips


def _tip_offsets(tree: KinematicTree, desc: RobotDescription, tips: list[str]) -> np.ndarray:
    """(m, 3) tip points in the fingertip link frames: each body's distal end pulled back by ``TIP_PULLBACK``
    towards the centroid, then moved onto the body's surface (a pad point, as the built-ins' offsets are)."""
    out = []
    for link in tips:
        b, T_bl = tree.link_body[link]
        meshes = [
            m.copy().apply_transform(T)
            for n, (bb, T) in tree.link_body.items()
            if bb == b
            for m in desc.links.get(n, [])
        ]
        if not meshes:
            out.append(np.zeros(3))
            continue
        body = cast(trimesh.Trimesh, trimesh.util.concatenate(meshes))
        v = np.asarray(body.vertices)
        far = v[np.argmax(np.linalg.norm(v, axis=1))]
        inner = far + TIP_PULLBACK * (v.mean(0) - far)
        on_surface, _, _ = trimesh.proximity.closest_point(body, inner[None])
        T_lb = np.linalg.inv(T_bl)
        out.append(T_lb[:3, :3] @ on_surface[0] + T_lb[:3, 3])
    return np.asarray(out)


def _weld(desc: RobotDescription) -> None:
    """Merge each mesh's duplicate vertices (STL files and MuJoCo's compiled meshes are triangle soups): a closed
    mesh is then one watertight part, which the pads' convex parts and the penetration checks rely on."""
    for meshes in desc.links.values():
        for mesh in meshes:
            mesh.merge_vertices()
            mesh.remove_unreferenced_vertices()


def pad_areas(hand: Hand) -> list[float]:
    """(m,) m²: each fingertip pad's area, its body mesh's faces within ``PAD_RADIUS`` of the tip point."""
    areas = []
    for body, tip in zip(hand.fingertip_bodies, hand._tip_local, strict=True):
        mesh = hand.collision_meshes[body]
        near = np.linalg.norm(np.asarray(mesh.triangles_center) - tip, axis=1) <= PAD_RADIUS
        areas.append(float(np.asarray(mesh.area_faces)[near].sum()))
    return areas


def build_user_hand(src: HandSource) -> HandBuild:
    """Build a user's hand and its report (see module doc).

    Raises:
        HandLoadError: anything unsafe, malformed, missing or inconsistent (the message names it).
    """
    start = time.perf_counter()
    desc, fmt, member, meshes, ignored, palm, drawn = _parse(src)
    _weld(desc)
    tree = KinematicTree(desc)
    rest = src.rest if src.rest is not None else {k: v for k, v in drawn.items() if k in tree.joint_names}
    tips = list(src.fingertips) if src.fingertips else _default_fingertips(tree, desc)
    unknown = [t for t in tips if t not in tree.link_body]
    if unknown:
        raise HandLoadError(f"fingertips: {unknown} are not links below the palm {palm!r}")
    offsets = src.tip_offsets if src.tip_offsets is not None else _tip_offsets(tree, desc, tips)
    hand = Hand(desc, name=src.name, fingertips=tips, tip_offsets=offsets, rest=rest, approach_axis=src.approach_axis)
    _ = hand.contact_surface, hand.surface_points  # pads and the network's cloud, built (and timed) now
    if src.approach_axis is None:
        d = torch.float64
        zero, unit = torch.zeros(1, 3, dtype=d), torch.tensor([[1.0, 0, 0, 0]], dtype=d)
        centre = hand.fingertips(zero, unit, torch.as_tensor(hand.rest[None]))[0].numpy().mean(0)
        if np.linalg.norm(centre) > 1e-6:
            hand.approach_axis = centre / np.linalg.norm(centre)
    empty = [n for n in desc.links if not desc.links[n] and "__j" not in n]
    if empty:
        ignored.append(f"{len(empty)} links below the palm carry no geometry ({', '.join(empty[:4])})")
    open_bodies = [b for b, m in hand.collision_meshes.items() if not m.is_watertight]
    if open_bodies:
        ignored.append(
            f"{len(open_bodies)} of {len(hand.collision_meshes)} bodies have meshes that are not closed "
            f"({', '.join(open_bodies[:4])}): inside/outside, hence penetration, is approximate on them"
        )
    couplings = [f"joint {j.name!r} = {j.mimic[1]:.6g} * {j.mimic[0]!r} + {j.mimic[2]:.6g} (mimic, honoured)"
                 for j in desc.joints if j.mimic is not None and fmt == "urdf"]  # fmt: skip
    couplings += desc.couplings
    return HandBuild(
        hand=hand, format=fmt, description=member if src.archive is not None else "inline", palm=palm,
        fingertips=tips, pad_areas=pad_areas(hand), couplings=couplings, ignored=ignored,
        meshes=len(meshes.loaded) if meshes is not None else 0, seconds=time.perf_counter() - start,
    )  # fmt: skip
