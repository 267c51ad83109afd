"""Plan requests (``POST /v1/plans``) from a planner's few numbers: poses, boxes, a table; validated before sending.

Example::

    from manifoundation.sdk import Client, box_obstacle, make_plan, object_from_file

    plan = make_plan(
        object_from_file("examples/data/box.npz"), start=[0.3, 0, 0.03], waypoints=[[0.3, 0, 0.2], [0, 0.3, 0.2]],
        robot="allegro", obstacles=[box_obstacle([0.1, 0.1, 0.3], [0.15, 0.15, 0.15], name="kettle")],
        support_plane=0.0, method="random_contacts",
    )
    with Client() as client:
        result = client.plan(plan)
    print(result.success, len(result.positions), result.regrasps)
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from manifoundation.contract import BoxObstacleIn, ObjectIn, PlanOptions, PlanRequest, PoseIn, SceneIn, SupportPlaneIn
from manifoundation.sdk.errors import checked
from manifoundation.sdk.objects import ObjectLike, as_object
from manifoundation.sdk.requests import RobotLike, as_robot

PoseLike = PoseIn | Sequence[float] | np.ndarray | dict[str, Any]
"""A `PoseIn`, a position (3,) (identity orientation), ``[x, y, z, qw, qx, qy, qz]`` (7,), or a dict."""


def as_pose(value: PoseLike, field: str = "pose") -> PoseIn:
    """Coerce a position (3,), position + quaternion (7,), dict or `PoseIn` into a `PoseIn` (checked)."""
    if isinstance(value, PoseIn):
        return value
    if isinstance(value, dict):
        return checked(PoseIn, field, **value)
    row = np.asarray(value, dtype=np.float64).reshape(-1)
    if len(row) == 7:
        return checked(PoseIn, field, position=row[:3], quaternion=row[3:])
    return checked(PoseIn, field, position=row)


def box_obstacle(size: Sequence[float], position: Sequence[float], quaternion: Sequence[float] | None = None,
                 *, name: str | None = None) -> BoxObstacleIn:  # fmt: skip
    """A solid box of full extents ``size`` (m) centred at ``position`` (rotated by ``quaternion``, w x y z)."""
    rotation = (1.0, 0.0, 0.0, 0.0) if quaternion is None else quaternion
    pose = as_pose([*position, *rotation], "pose")
    return checked(BoxObstacleIn, "scene.obstacles", size=np.asarray(size, dtype=np.float64), pose=pose, name=name)


def make_plan(
    object: ObjectLike | PlanRequest,
    start: PoseLike | None = None,
    waypoints: Sequence[PoseLike] = (),
    robot: RobotLike = "allegro",
    *,
    obstacles: Sequence[Any] = (),
    support_plane: float | SupportPlaneIn | None = None,
    **options: Any,
) -> PlanRequest:
    """Build and validate a `PlanRequest`.

    Args:
        object: anything `as_object` takes (a rigid object, in its own frame), or a whole `PlanRequest` (returned
            as it is).
        start: the object's pose now (default: its frame at the world origin).
        waypoints: the poses it should pass through, in order (1 to 64).
        robot: a hand name, `RobotIn` or dict.
        obstacles: `BoxObstacleIn` / `MeshObstacleIn` / `PointCloudObstacleIn` models or their dicts.
        support_plane: a table's height z (m), or a `SupportPlaneIn`; None: no table.
        **options: `PlanOptions` fields: ``method``, ``seed``, ``translation_step``, ``repair``, ``timeout``, ...

    Raises:
        ValidationError: a field that breaks the contract, named as the service would name it.
    """
    if isinstance(object, PlanRequest):
        return object
    obj: ObjectIn = as_object(object)
    plane = SupportPlaneIn(height=float(support_plane)) if isinstance(support_plane, int | float) else support_plane
    scene = checked(SceneIn, "scene", obstacles=list(obstacles), support_plane=plane)
    return checked(
        PlanRequest, "", object=obj, start=as_pose(start if start is not None else [0.0, 0.0, 0.0], "start"),
        waypoints=[as_pose(w, f"waypoints.{i}") for i, w in enumerate(waypoints)], scene=scene,
        robot=as_robot(robot), options=checked(PlanOptions, "options", **options),
    )  # fmt: skip
