"""A plotly figure that plays a plan: the scene, the object's path, and per step (a slider) the object, the hand
(its coarse meshes, posed) and the contacts; re-grasp steps are marked on the slider."""

from __future__ import annotations

from typing import Any

import numpy as np

from manifoundation.core.planning.obstacles import SupportPlane
from manifoundation.core.planning.scene import CollisionScene
from manifoundation.core.planning.types import PlanOutput, PlanStep
from manifoundation.core.robots.hand import Hand
from manifoundation.core.robots.view import posed_mesh

OBSTACLE_COLOUR, OBJECT_COLOUR, HAND_COLOUR = "#9aa0a6", "#e07b39", "#7da7d9"


def _mesh_trace(vertices: np.ndarray, faces: np.ndarray, colour: str, name: str, opacity: float = 1.0) -> Any:
    import plotly.graph_objects as go

    v, f = np.asarray(vertices), np.asarray(faces)
    return go.Mesh3d(x=v[:, 0], y=v[:, 1], z=v[:, 2], i=f[:, 0], j=f[:, 1], k=f[:, 2], color=colour,
                     opacity=opacity, name=name, flatshading=True, hoverinfo="name")  # fmt: skip


def hand_mesh(hand: Hand, step: PlanStep) -> tuple[np.ndarray, np.ndarray]:
    """The step's hand as one world mesh: vertices (V, 3), faces (F, 3) (`manifoundation.core.robots.view`)."""
    assert step.proposal is not None
    p = step.proposal
    return posed_mesh(hand, np.asarray(p.palm_position), np.asarray(p.palm_quaternion), np.asarray(p.joint_values))


def _plane_trace(support: SupportPlane, centre: np.ndarray, half: float) -> Any:
    import plotly.graph_objects as go

    xs = np.array([centre[0] - half, centre[0] + half])
    ys = np.array([centre[1] - half, centre[1] + half])
    return go.Surface(x=xs, y=ys, z=np.full((2, 2), support.height), showscale=False, opacity=0.3,
                      colorscale=[[0, "#c8b99a"], [1, "#c8b99a"]], name="support plane", hoverinfo="name")  # fmt: skip


def plan_figure(plan: PlanOutput, scene: CollisionScene, hand: Hand | None = None) -> Any:
    """A ``plotly.graph_objects.Figure`` of ``plan`` in ``scene`` (world frame, metres).

    Args:
        plan: the plan.
        scene: its collision world (obstacles, support plane, the object's collision mesh).
        hand: the hand, to draw it at each step (None: the object only).
    """
    import plotly.graph_objects as go

    static: list[Any] = [_mesh_trace(np.asarray(o.mesh().vertices), np.asarray(o.mesh().faces), OBSTACLE_COLOUR,
                                     name) for o, name in zip(scene.obstacles, scene.names, strict=True)]  # fmt: skip
    pos = np.array([p.position for p in plan.poses])
    if scene.support is not None:
        static.append(_plane_trace(scene.support, pos.mean(0), float(np.ptp(pos, axis=0).max()) / 2 + 0.3))
    static.append(go.Scatter3d(x=pos[:, 0], y=pos[:, 1], z=pos[:, 2], mode="lines", line={"color": "black"},
                               name="object path"))  # fmt: skip
    way = pos[plan.waypoint_indices]
    static.append(go.Scatter3d(x=way[:, 0], y=way[:, 1], z=way[:, 2], mode="markers", name="waypoints",
                               marker={"size": 5, "color": "black"}))  # fmt: skip
    for r in plan.repairs:
        a, b = r.requested.position, r.repaired.position
        static.append(go.Scatter3d(x=[a[0], b[0]], y=[a[1], b[1]], z=[a[2], b[2]], mode="lines+markers",
                                   line={"color": "red", "dash": "dash"}, marker={"size": 3, "color": "red"},
                                   name=f"waypoints[{r.index}] repaired ({1000 * r.distance:.0f} mm)"))  # fmt: skip
    count = len(plan.poses)

    def moving(k: int) -> list[Any]:
        pose = plan.poses[k]
        body = pose.apply(scene.object_vertices)
        traces = [_mesh_trace(body, scene.object_faces, OBJECT_COLOUR, f"object, pose {k}")]
        step = plan.steps[k] if k < len(plan.steps) else None
        if hand is None or not plan.steps:
            return traces
        if step is not None and step.proposal is not None:
            v, f = hand_mesh(hand, step)
            c = step.proposal.contact_points
            colour, label = (HAND_COLOUR if step.success else "#d93025"), f"hand, step {k}: {step.grasp}"
        else:  # the final pose (or a step without an answer): no hand; same trace count in every frame
            v, f, c, colour, label = np.zeros((3, 3)), np.array([[0, 1, 2]]), np.zeros((0, 3)), HAND_COLOUR, "hand"
        traces.append(_mesh_trace(v, f, colour, label, opacity=0.7))
        traces.append(go.Scatter3d(x=c[:, 0], y=c[:, 1], z=c[:, 2], mode="markers", name="contacts",
                                   marker={"size": 4, "color": "#188038"}))  # fmt: skip
        return traces

    first = moving(0)
    fig = go.Figure(static + first)
    moving_idx = list(range(len(static), len(static) + len(first)))
    frames, labels = [], []
    for k in range(count):
        traces = moving(k)
        frames.append(go.Frame(data=traces, traces=moving_idx[: len(traces)], name=str(k)))
        grasp = plan.steps[k].grasp if k < len(plan.steps) else ""
        labels.append(f"{k}{'*' if grasp in ('regrasp', 'failed') else ''}")
    fig.frames = frames
    slider = {"steps": [{"args": [[str(k)], {"frame": {"duration": 0, "redraw": True}, "mode": "immediate"}],
                         "label": labels[k], "method": "animate"} for k in range(count)],
              "currentvalue": {"prefix": "step (* = re-grasp or failed): "}}  # fmt: skip
    play = {"type": "buttons", "buttons": [{"label": "play", "method": "animate",
                                            "args": [None, {"frame": {"duration": 150, "redraw": True}}]}]}  # fmt: skip
    kept = f", {100 * plan.kept_share:.0f}% of steps keep the grasp" if plan.steps else ""
    fig.update_layout(title=f"plan: {len(plan.poses)} poses, {len(plan.repairs)} repaired waypoints{kept}",
                      scene={"aspectmode": "data"}, sliders=[slider], updatemenus=[play])  # fmt: skip
    return fig
