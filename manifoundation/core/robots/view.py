"""What viewers draw of a hand: its coarse meshes and spheres posed anywhere (a proposal's pose, a plan's step), a
light preview at rest (coarse meshes, spheres, pads, tips) for the service's robot page, and a plotly figure.

One coarse mesh per body, computed once per hand: the collision mesh itself when it is small, else the convex hulls
of its parts (LEAP's fingertips have 7 000 faces), each hull of at most ``PART_VERTICES`` spread vertices."""

from __future__ import annotations

import weakref
from dataclasses import dataclass
from typing import Any

import numpy as np
import torch
import trimesh

from manifoundation.core.robots.hand import Hand


def _sphere_mesh(c: np.ndarray, r: float, n: int = 10) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    u, v = np.meshgrid(np.linspace(0, 2 * np.pi, n), np.linspace(0, np.pi, n))
    return c[0] + r * np.cos(u) * np.sin(v), c[1] + r * np.sin(u) * np.sin(v), c[2] + r * np.cos(v)


def hand_figure(hand: Hand, normal_length: float = 0.01) -> Any:
    """A ``plotly.graph_objects.Figure`` of ``hand`` at rest, palm frame (metres)."""
    import plotly.graph_objects as go

    d = torch.float64
    pos, quat, q = torch.zeros(1, 3, dtype=d), torch.tensor([[1.0, 0, 0, 0]], dtype=d), torch.as_tensor(hand.rest[None])
    poses = {k: v[0].numpy() for k, v in hand.link_poses(pos, quat, q).items()}
    traces: list[Any] = []
    for link, mesh in hand.collision_meshes.items():
        T = poses[link]
        v = np.asarray(mesh.vertices) @ T[:3, :3].T + T[:3, 3]
        f = np.asarray(mesh.faces)
        traces.append(
            go.Mesh3d(
                x=v[:, 0],
                y=v[:, 1],
                z=v[:, 2],
                i=f[:, 0],
                j=f[:, 1],
                k=f[:, 2],
                name=link,
                color="lightsteelblue",
                opacity=0.6,
                legendgroup="meshes",
                showlegend=False,
            )
        )
    centres, _ = hand.spheres(pos, quat, q, jacobian=False)
    for c, r in zip(centres[0].numpy(), hand.sphere_radii, strict=True):
        x, y, z = _sphere_mesh(c, float(r))
        traces.append(
            go.Surface(
                x=x,
                y=y,
                z=z,
                opacity=0.25,
                showscale=False,
                colorscale=[[0, "orange"], [1, "orange"]],
                legendgroup="spheres",
                showlegend=False,
                hoverinfo="skip",
            )
        )
    p, n = hand.surface_points, hand.surface_normals
    traces.append(
        go.Scatter3d(
            x=p[:, 0], y=p[:, 1], z=p[:, 2], mode="markers", marker={"size": 2, "color": "black"}, name="surface points"
        )
    )
    seg = np.full((3 * len(p), 3), np.nan)
    seg[0::3], seg[1::3] = p, p + normal_length * n
    traces.append(
        go.Scatter3d(
            x=seg[:, 0], y=seg[:, 1], z=seg[:, 2], mode="lines", line={"color": "green", "width": 1}, name="normals"
        )
    )
    tips = hand.fingertips(pos, quat, q)[0].numpy()
    traces.append(
        go.Scatter3d(
            x=tips[:, 0],
            y=tips[:, 1],
            z=tips[:, 2],
            mode="markers+text",
            text=hand.fingertip_links,
            marker={"size": 6, "color": "red"},
            name="fingertips",
        )
    )
    a = 0.05 * hand.approach_axis
    traces.append(
        go.Scatter3d(
            x=[0, a[0]],
            y=[0, a[1]],
            z=[0, a[2]],
            mode="lines",
            line={"color": "blue", "width": 6},
            name="approach axis",
        )
    )
    fig = go.Figure(traces)
    fig.update_layout(
        title=f"{hand.name}: {hand.dof} DoF, {hand.num_fingertips} tips, {len(hand.sphere_radii)} spheres (rest)",
        scene={"aspectmode": "data"},
    )
    return fig


PREVIEW_PART_VERTICES = 48
"""A preview draws each connected part of a body mesh as the hull of at most this many of its vertices."""
PREVIEW_PADS = 600


@dataclass
class RestPreview:
    """A hand at rest in its palm frame, light enough to send to a browser.

    Attributes:
        vertices, faces: (V, 3), (F, 3) coarse collision meshes (hulls of each connected part).
        spheres: (S, 4) collision sphere centres and radii.
        pads: (P, 3) contact-pad samples (at most ``PREVIEW_PADS``).
        tips: (m, 3) fingertip points.
    """

    vertices: np.ndarray
    faces: np.ndarray
    spheres: np.ndarray
    pads: np.ndarray
    tips: np.ndarray


SMALL_MESH_FACES = 400
"""A body mesh with more faces is drawn as the convex hulls of its parts ..."""
PART_VERTICES = PREVIEW_PART_VERTICES
"""... each hull of at most this many of the part's vertices (farthest-point sampling)."""
MAX_PARTS = 32
_COARSE: weakref.WeakKeyDictionary[Hand, dict[str, tuple[np.ndarray, np.ndarray]]] = weakref.WeakKeyDictionary()


def coarse_meshes(hand: Hand) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Body → its coarse mesh in the body's frame: vertices (V, 3), faces (F, 3); computed once per hand."""
    if hand not in _COARSE:
        _COARSE[hand] = {body: _coarse(mesh) for body, mesh in hand.collision_meshes.items() if len(mesh.faces)}
    return _COARSE[hand]


def _coarse(mesh: trimesh.Trimesh) -> tuple[np.ndarray, np.ndarray]:
    if len(mesh.faces) <= SMALL_MESH_FACES:
        return np.asarray(mesh.vertices, dtype=np.float64), np.asarray(mesh.faces, dtype=np.int64)
    from manifoundation.core.robots.spheres import farthest_points

    pieces = [p for p in mesh.split(only_watertight=False) if len(p.faces) >= 4] or [mesh]
    verts: list[np.ndarray] = []
    faces: list[np.ndarray] = []
    offset = 0
    for piece in pieces[:MAX_PARTS]:
        v = np.asarray(piece.vertices)
        try:
            hull = trimesh.convex.convex_hull(v[farthest_points(v, PART_VERTICES)])
        except Exception:  # a flat piece has no hull: draw nothing of it
            continue
        verts.append(np.asarray(hull.vertices))
        faces.append(np.asarray(hull.faces) + offset)
        offset += len(hull.vertices)
    if not verts:
        return np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64)
    return np.vstack(verts), np.vstack(faces).astype(np.int64)


def _row(a: np.ndarray) -> torch.Tensor:
    return torch.as_tensor(np.asarray(a, dtype=np.float64))[None]


def posed_mesh(hand: Hand, palm_position: np.ndarray, palm_quaternion: np.ndarray,
               q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """The hand's coarse meshes posed (palm (3,), quaternion (4,) w-first, joints (D,)), merged into one world
    mesh: vertices (V, 3), faces (F, 3)."""
    with torch.no_grad():
        poses = hand.link_poses(_row(palm_position), _row(palm_quaternion), _row(q))
    verts: list[np.ndarray] = []
    faces: list[np.ndarray] = []
    offset = 0
    for body, (v, f) in coarse_meshes(hand).items():
        T = poses[body][0].numpy()
        verts.append(v @ T[:3, :3].T + T[:3, 3])
        faces.append(f + offset)
        offset += len(v)
    if not verts:
        return np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64)
    return np.vstack(verts), np.vstack(faces).astype(np.int64)


def posed_spheres(hand: Hand, palm_position: np.ndarray, palm_quaternion: np.ndarray, q: np.ndarray) -> np.ndarray:
    """The hand's collision spheres at a pose, (S, 4): world centre and radius."""
    with torch.no_grad():
        centres, _ = hand.spheres(_row(palm_position), _row(palm_quaternion), _row(q), jacobian=False)
    return np.hstack([centres[0].numpy(), np.asarray(hand.sphere_radii, dtype=np.float64)[:, None]])


def rest_preview(hand: Hand) -> RestPreview:
    """The hand at its rest pose (palm frame): see :class:`RestPreview`."""
    d = torch.float64
    pos, quat, q = torch.zeros(1, 3, dtype=d), torch.tensor([[1.0, 0, 0, 0]], dtype=d), torch.as_tensor(hand.rest[None])
    with torch.no_grad():
        surf = hand.contact_surface
        pad = np.flatnonzero(surf.pad)[:: max(1, int(np.ceil(surf.pad.sum() / PREVIEW_PADS)))]
        pts, _, _ = hand.surface_samples(pos, quat, q, index=pad, jacobian=False)
        tips = hand.fingertips(pos, quat, q)[0].numpy()
    rest = (np.zeros(3), np.array([1.0, 0, 0, 0]), np.asarray(hand.rest, dtype=np.float64))
    vertices, faces = posed_mesh(hand, *rest)
    return RestPreview(vertices=vertices, faces=faces, spheres=posed_spheres(hand, *rest), pads=pts[0].numpy(),
                       tips=tips)  # fmt: skip
