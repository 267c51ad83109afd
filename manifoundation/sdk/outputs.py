"""Results out: plain dicts and JSON for logs and files, and a plotly 3D figure of a grasp.

The figure draws what the service's viewer draws (``GET /v1/jobs/{id}/view``): the object's points (coloured by
the contact heatmap when the result carries one), the contacts, force arrows, the palm frame and the hand as
links from the palm to its fingertips, titled with the quality figures. plotly is
imported only when a figure is made.
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

import numpy as np

from manifoundation.contract import ObjectIn, PhysicsQuality, Proposal, SynthesisResult
from manifoundation.sdk.extras import require


def result_to_dict(result: SynthesisResult) -> dict[str, Any]:
    """The result as plain JSON-ready data (arrays as nested lists, unset fields left out)."""
    return result.model_dump(mode="json", exclude_none=True)


def result_to_json(result: SynthesisResult, path: str | os.PathLike[str] | None = None, *, indent: int = 2) -> str:
    """The result as JSON text; also written to ``path`` when given."""
    text = json.dumps(result_to_dict(result), indent=indent)
    if path is not None:
        Path(path).write_text(text + "\n", encoding="utf-8")
    return text


def load_result(path: str | os.PathLike[str]) -> SynthesisResult:
    """Read a result written by `result_to_json` (arrays come back as numpy arrays)."""
    return SynthesisResult.model_validate_json(Path(path).read_bytes())


def quality_text(proposal: Proposal) -> str:
    """One line of a proposal's quality figures."""
    q = proposal.quality
    parts = [
        "success" if q.success else "FAILED",
        f"{q.reason} after {q.iterations} it",
        f"residual {q.wrench_residual:.2e}",
        f"tip {q.max_tip_distance * 1000:.1f} mm",
        f"penetration {q.penetration_depth * 1000:.1f} mm",
    ]
    if q.epsilon is not None:
        parts.append(f"ε {q.epsilon:.3f}")
    if q.physics is not None:
        parts.append(physics_text(q.physics))
    return ", ".join(parts)


def physics_text(physics: PhysicsQuality) -> str:
    """The simulated test's verdict in a few words: held / reached, or why not with the worst push or the motion's
    final error."""
    if physics.test == "motion":
        m = physics.motion
        where = "" if m is None else f" ({m.translation_error * 100:.1f} cm, {m.rotation_error:.0f}° off)"
        return ("physics: reached" if physics.held else f"physics: {physics.reason}") + where
    if physics.held:
        worst = max((t.translation for t in physics.trials), default=0.0)
        return f"physics: held (moved ≤ {worst * 100:.1f} cm)"
    failed = [t for t in physics.trials if not t.held]
    if not failed:
        return f"physics: {physics.reason}"
    t = max(failed, key=lambda t: t.translation)
    return f"physics: {physics.reason} (push {t.direction}: {t.translation * 100:.1f} cm, {t.rotation:.0f}°)"


def _rotation(q: np.ndarray) -> np.ndarray:
    w, x, y, z = q / np.linalg.norm(q)
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


def result_figure(
    result: SynthesisResult,
    object: ObjectIn | None = None,
    *,
    proposal: int | None = None,
    force_scale: float | None = None,
    title: str | None = None,
) -> Any:
    """A plotly ``Figure`` of one proposal, drawn like the service's viewer (``/v1/jobs/{id}/view``).

    The object's points are coloured by the contact heatmap when the result has one (else by the region mask,
    else by height); then the contacts labelled with their fingertips, the force arrows, the palm frame, and the
    hand: its posed collision meshes when the result has them (``options.return_hand_mesh``), else links from the
    palm to each fingertip at its contact.

    Args:
        result: the answer of `synthesize`.
        object: the object that was sent (its points are drawn; without it only the grasp is).
        proposal: which proposal (default: ``result.best``).
        force_scale: metres of arrow per newton (default: the longest arrow is 35 % of the object's size).
        title: figure title (default: hand, proposal and quality).

    Returns:
        ``plotly.graph_objects.Figure``; ``fig.write_html("grasp.html")`` or ``fig.show()``.
    """
    go = require("plotly.graph_objects", "view", "result_figure")

    chosen = result.best if proposal is None else result.proposals[proposal]
    fig = go.Figure()
    reference = object.points if object is not None else chosen.contact_points if chosen is not None else None
    size = float(np.max(np.ptp(reference, axis=0))) if reference is not None and len(reference) > 1 else 0.1
    size = size or 0.1
    if object is not None:
        pts = object.points
        heat = result.heatmap if result.heatmap is not None and len(result.heatmap) == len(pts) else None
        colour = heat if heat is not None else object.region_mask if object.region_mask is not None else pts[:, 2]
        marker: dict[str, Any] = {"size": 2, "color": np.asarray(colour, dtype=float)}
        marker.update(colorscale="YlOrRd" if heat is not None else "Greys", showscale=heat is not None)
        if heat is not None:
            marker["colorbar"] = {"title": "heat", "len": 0.5}
        name = "object (heatmap)" if heat is not None else "object"
        fig.add_trace(go.Scatter3d(x=pts[:, 0], y=pts[:, 1], z=pts[:, 2], mode="markers", marker=marker, name=name))
    if chosen is not None:
        _grasp_traces(fig, chosen, size, force_scale)
        _deformable_traces(fig, chosen)
    index = result.proposals.index(chosen) if chosen is not None else 0
    quality = quality_text(chosen) if chosen is not None else "no proposal"
    heading = title or f"{result.hand}, proposal {index}<br><sup>{quality}</sup>"
    fig.update_layout(
        title={"text": heading, "x": 0.01, "font": {"size": 15}},
        scene={"aspectmode": "data"},
        margin={"l": 0, "r": 0, "t": 60, "b": 0},
        legend={"x": 0, "y": 0.9},
    )
    return fig


def _deformable_traces(fig: Any, p: Proposal) -> None:
    """A deformable answer's post-contact motions (to scale) and, when simulated, its rollout."""
    import plotly.graph_objects as go

    if p.contact_motions is not None:
        xs, ys, zs = _segments(p.contact_points, p.contact_points + p.contact_motions)
        line = {"color": "#9467bd", "width": 6}
        fig.add_trace(go.Scatter3d(x=xs, y=ys, z=zs, mode="lines", line=line, name="post-contact motions"))
    if p.rollout_points is not None:
        r = p.rollout_points
        marker = {"size": 2, "color": "#ff7f0e"}
        fig.add_trace(go.Scatter3d(x=r[:, 0], y=r[:, 1], z=r[:, 2], mode="markers", marker=marker,
                                   name="rollout (simulated)"))  # fmt: skip


def _grasp_traces(fig: Any, p: Proposal, size: float, force_scale: float | None) -> None:
    go = require("plotly.graph_objects", "view", "result_figure")

    c, f = p.contact_points, p.forces
    fig.add_trace(
        go.Scatter3d(
            x=c[:, 0],
            y=c[:, 1],
            z=c[:, 2],
            mode="markers+text",
            text=p.fingertips,
            textposition="top center",
            marker={"size": 7, "color": "#d62728"},
            name="contacts",
        )
    )
    norms = np.linalg.norm(f, axis=1)
    scale = force_scale if force_scale is not None else 0.35 * size / max(float(norms.max(initial=0)), 1e-9)
    tips = c + f * scale
    xs, ys, zs = _segments(c, tips)
    fig.add_trace(go.Scatter3d(x=xs, y=ys, z=zs, mode="lines", line={"color": "#1f77b4", "width": 6}, name="forces"))
    if len(c) and float(norms.max(initial=0)) > 0:
        fig.add_trace(
            go.Cone(
                x=tips[:, 0],
                y=tips[:, 1],
                z=tips[:, 2],
                u=f[:, 0],
                v=f[:, 1],
                w=f[:, 2],
                anchor="tip",
                sizemode="absolute",
                sizeref=0.08 * size,
                showscale=False,
                colorscale=[[0, "#1f77b4"], [1, "#1f77b4"]],
                name="force heads",
            )
        )
    if p.palm_position is None or p.palm_quaternion is None:
        return  # contacts without a robot: no hand to draw
    palm, rot = p.palm_position, _rotation(p.palm_quaternion)
    for axis, colour in enumerate(("#e41a1c", "#4daf4a", "#377eb8")):
        end = palm + rot[:, axis] * 0.4 * size
        fig.add_trace(
            go.Scatter3d(
                x=[palm[0], end[0]],
                y=[palm[1], end[1]],
                z=[palm[2], end[2]],
                mode="lines",
                line={"color": colour, "width": 8},
                name="palm frame",
                legendgroup="palm",
                showlegend=axis == 0,
            )
        )
    if p.hand_mesh is not None and len(p.hand_mesh.vertices):
        v, tri = p.hand_mesh.vertices, p.hand_mesh.faces
        fig.add_trace(
            go.Mesh3d(
                x=v[:, 0], y=v[:, 1], z=v[:, 2], i=tri[:, 0], j=tri[:, 1], k=tri[:, 2], color="#c49c94",
                opacity=0.55, flatshading=True, hoverinfo="skip", name="hand (collision meshes)", showlegend=True,
            )
        )  # fmt: skip
    else:
        xs, ys, zs = _segments(np.repeat(palm[None], len(c), axis=0), c)
        fig.add_trace(
            go.Scatter3d(
                x=xs,
                y=ys,
                z=zs,
                mode="lines",
                line={"color": "#8c564b", "width": 10},
                opacity=0.6,
                name="hand (palm → fingertips)",
            )
        )
    fig.add_trace(
        go.Scatter3d(
            x=[palm[0]],
            y=[palm[1]],
            z=[palm[2]],
            mode="markers",
            name="palm",
            marker={"size": 14, "color": "#8c564b", "symbol": "square"},
        )
    )
    fig.add_trace(
        go.Scatter3d(
            x=c[:, 0],
            y=c[:, 1],
            z=c[:, 2],
            mode="markers",
            name="fingertips",
            marker={"size": 12, "color": "#ff7f0e", "opacity": 0.35},
        )
    )


def _segments(start: np.ndarray, end: np.ndarray) -> tuple[list[float | None], ...]:
    """Line segments as one plotly trace (None breaks the line between segments)."""
    out: tuple[list[float | None], ...] = ([], [], [])
    for a, b in zip(start, end, strict=True):
        for k in range(3):
            out[k].extend([float(a[k]), float(b[k]), None])
    return out
