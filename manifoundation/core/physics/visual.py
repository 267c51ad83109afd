"""The hand's geometry as the physics test sees it: real (visual) meshes wherever a link's collision geometry is
only a primitive cover.

A URDF link whose ``<collision>`` elements are all primitives (box, sphere, cylinder, capsule) and that has a
``<visual>`` mesh is read from its visual meshes (Allegro's boxes and tip spheres become its real links); links whose
collision geometry is a mesh keep it (the Panda's STL meshes). Hands without such a source (MJCF hands, user hands,
``leap_kaizen`` whose description already is its visual meshes' hulls) keep the geometry they were built from.
MuJoCo collides each mesh as its convex hull.
"""

from __future__ import annotations

import functools
from typing import TYPE_CHECKING

from manifoundation.core.robots.description import RobotDescription

if TYPE_CHECKING:
    from manifoundation.core.robots.hand import Hand



@functools.cache
def _cached(name: str, palm: str) -> RobotDescription | None:
    from manifoundation.core.robots.registry import real_surface_description

    full = real_surface_description(name)
    if full is None:
        return None
    return full.subtree(palm) if palm in full.links else full


def physics_description(hand: Hand) -> RobotDescription:
    """The hand below its palm, with the meshes the physics test collides (see module doc)."""
    palm = hand.tree.body_names[0]
    from manifoundation.core.robots.registry import get_hand, list_hands

    builtin = hand.name in list_hands(aliases=True) and get_hand(hand.name) is hand
    desc = _cached(hand.name, palm) if builtin else None
    if desc is None:
        base = hand.description
        desc = base.subtree(palm) if palm != base.root else base
    return desc
