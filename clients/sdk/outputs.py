"""Results out: plain dicts and JSON for logs and files, and a plotly 3D figure of a grasp.

The figure shows what the service's viewer shows: the object's points (coloured by the contact heatmap when the
result carries one), the contact points, force arrows, the palm frame and the quality figures. plotly is
imported only when a figure is made.
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

import numpy as np

from clients.schemas import ObjectIn, Proposal, SynthesisResult


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
    return ", ".join(parts)


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
    """A plotly ``Figure`` of one proposal: object points, contacts, force arrows and palm frame.

    Args:
        result: the answer of `synthesize`.
        object: the object that was sent (its points are drawn; without it only the grasp is).
        proposal: which proposal (default: ``result.best``).
        force_scale: metres of arrow per newton (default: the longest arrow is 30 % of the object's size).
        title: figure title (default: hand, proposal and quality).

    Returns:
        ``plotly.graph_objects.Figure``; ``fig.write_html("grasp.html")`` or ``fig.show()``.
    """
    import plotly.graph_objects as go

    chosen = result.best if proposal is None else result.proposals[proposal]
    fig = go.Figure()
    size = 0.1
    if object is not None:
        pts = object.points
        size = float(np.max(np.ptp(pts, axis=0))) or size
        heat = result.heatmap if result.heatmap is not None and len(result.heatmap) == len(pts) else None
        marker: dict[str, Any] = {"size": 2, "color": "lightgray" if heat is None else heat}
        if heat is not None:
            marker.update(colorscale="Viridis", colorbar={"title": "contact"}, cmin=0.0, cmax=1.0)
        fig.add_trace(go.Scatter3d(x=pts[:, 0], y=pts[:, 1], z=pts[:, 2], mode="markers", marker=marker, name="object"))
    if chosen is not None:
        c, f = chosen.contact_points, chosen.forces
        fig.add_trace(
            go.Scatter3d(
                x=c[:, 0],
                y=c[:, 1],
                z=c[:, 2],
                mode="markers+text",
                text=chosen.fingertips,
                marker={"size": 6, "color": "red"},
                name="contacts",
            )
        )
        norms = np.linalg.norm(f, axis=1)
        scale = force_scale if force_scale is not None else 0.3 * size / max(float(norms.max(initial=0)), 1e-9)
        tips = c + f * scale
        xs, ys, zs = _segments(c, tips)
        fig.add_trace(go.Scatter3d(x=xs, y=ys, z=zs, mode="lines", line={"color": "orange", "width": 6}, name="forces"))
        palm, rot = chosen.palm_position, _rotation(chosen.palm_quaternion)
        for axis, colour in zip(range(3), ("red", "green", "blue"), strict=True):
            end = palm + rot[:, axis] * 0.3 * size
            fig.add_trace(
                go.Scatter3d(
                    x=[palm[0], end[0]],
                    y=[palm[1], end[1]],
                    z=[palm[2], end[2]],
                    mode="lines",
                    line={"color": colour, "width": 4},
                    name=f"palm {'xyz'[axis]}",
                    showlegend=axis == 0,
                )
            )
        xs, ys, zs = _segments(np.repeat(palm[None], len(c), axis=0), c)
        fig.add_trace(
            go.Scatter3d(
                x=xs,
                y=ys,
                z=zs,
                mode="lines",
                line={"color": "gray", "width": 2, "dash": "dot"},
                name="palm → contacts",
            )
        )
    index = result.proposals.index(chosen) if chosen is not None else 0
    heading = title or f"{result.hand}, proposal {index}: " + (quality_text(chosen) if chosen else "no proposal")
    fig.update_layout(title=heading, scene={"aspectmode": "data"}, margin={"l": 0, "r": 0, "t": 40, "b": 0})
    return fig


def _segments(start: np.ndarray, end: np.ndarray) -> tuple[list[float | None], ...]:
    """Line segments as one plotly trace (None breaks the line between segments)."""
    out: tuple[list[float | None], ...] = ([], [], [])
    for a, b in zip(start, end, strict=True):
        for k in range(3):
            out[k].extend([float(a[k]), float(b[k]), None])
    return out
