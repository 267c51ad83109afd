"""Wire ↔ science for registered hands: `RobotRegister` → `manifoundation.core.robots.user_hand.HandSource`, a built
hand → `RobotPublic` (with its report and rest preview).

Imported in the worker process only (it imports `models`, hence torch).
"""

from __future__ import annotations

import numpy as np

from manifoundation.contract import RobotPreview, RobotPublic, RobotRegister
from manifoundation.core.robots.user_hand import HandBuild, HandSource, build_user_hand
from manifoundation.core.robots.view import rest_preview


def hand_source(robot: RobotRegister) -> HandSource:
    """The core input of a registration."""
    return HandSource(
        name=robot.name, archive=robot.archive, urdf=robot.urdf, mjcf=robot.mjcf, palm=robot.palm,
        fingertips=list(robot.fingertips) if robot.fingertips else None,
        tip_offsets=None if robot.tip_offsets is None else np.asarray(robot.tip_offsets, dtype=np.float64),
        rest=dict(robot.rest) if robot.rest else None,
        approach_axis=None if robot.approach_axis is None else np.asarray(robot.approach_axis, dtype=np.float64),
        description=robot.description,
    )  # fmt: skip


def build_robot(robot: RobotRegister) -> HandBuild:
    """Build a registered hand.

    Raises `manifoundation.core.robots.HandLoadError` (a `ValueError`) naming the problem.
    """
    return build_user_hand(hand_source(robot))


def robot_public(build: HandBuild, robot: RobotRegister) -> RobotPublic:
    """What the service says about a registered hand (its report and preview included)."""
    hand = build.hand
    p = rest_preview(hand)
    preview = RobotPreview(vertices=p.vertices, faces=p.faces, spheres=p.spheres, pads=p.pads, tips=p.tips)
    return RobotPublic(
        name=robot.name, builtin=False, dof=int(hand.dof), joint_names=list(hand.joint_names),
        lower=[float(x) for x in hand.lower], upper=[float(x) for x in hand.upper],
        fingertips=list(hand.fingertip_links), num_spheres=len(hand.sphere_radii), source="user",
        palm=build.palm, format=build.format, surface_points=len(hand.surface_points),
        pad_area_cm2=[round(a * 1e4, 3) for a in build.pad_areas], couplings=build.couplings, ignored=build.ignored,
        meshes=build.meshes, registration_s=round(build.seconds, 3), stored_bytes=robot.stored_bytes, preview=preview,
    )  # fmt: skip
