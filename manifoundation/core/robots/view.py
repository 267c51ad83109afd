"""A hand at its rest pose: a plotly figure (collision meshes, spheres, surface points + normals) and a light preview
(coarse meshes, spheres, pads, tips) that the service's robot page draws."""

from __future__ import annotations

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


def _coarse_parts(mesh: trimesh.Trimesh) -> list[trimesh.Trimesh]:
    from manifoundation.core.robots.spheres import farthest_points

    pieces = [p for p in mesh.split(only_watertight=False) if len(p.faces) >= 4] or [mesh]
    out = []
    for piece in pieces[:32]:
        v = np.asarray(piece.vertices)
        pick = farthest_points(v, PREVIEW_PART_VERTICES)
        try:
            out.append(trimesh.convex.convex_hull(v[pick]))
        except Exception:  # a flat piece has no hull: draw nothing of it
            continue
    return out


def rest_preview(hand: Hand) -> RestPreview:
    """The hand at its rest pose (palm frame): see :class:`RestPreview`."""
    d = torch.float64
    pos, quat, q = torch.zeros(1, 3, dtype=d), torch.tensor([[1.0, 0, 0, 0]], dtype=d), torch.as_tensor(hand.rest[None])
    with torch.no_grad():
        poses = {k: v[0].numpy() for k, v in hand.link_poses(pos, quat, q).items()}
        centres, _ = hand.spheres(pos, quat, q, jacobian=False)
        surf = hand.contact_surface
        pad = np.flatnonzero(surf.pad)[:: max(1, int(np.ceil(surf.pad.sum() / PREVIEW_PADS)))]
        pts, _, _ = hand.surface_samples(pos, quat, q, index=pad, jacobian=False)
        tips = hand.fingertips(pos, quat, q)[0].numpy()
    verts, faces, offset = [], [], 0
    for body, mesh in hand.collision_meshes.items():
        T = poses[body]
        for part in _coarse_parts(mesh):
            verts.append(np.asarray(part.vertices) @ T[:3, :3].T + T[:3, 3])
            faces.append(np.asarray(part.faces) + offset)
            offset += len(part.vertices)
    spheres = np.hstack([centres[0].numpy(), np.asarray(hand.sphere_radii)[:, None]])
    return RestPreview(
        vertices=np.vstack(verts) if verts else np.zeros((0, 3)),
        faces=np.vstack(faces).astype(np.int64) if faces else np.zeros((0, 3), dtype=np.int64),
        spheres=spheres, pads=pts[0].numpy(), tips=tips,
    )  # fmt: skip
