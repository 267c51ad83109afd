"""A URDF hand's real surfaces: its visual meshes wherever a link's collision geometry is only a primitive cover.

Allegro's description collides through boxes around its phalanges and 12 mm spheres on its tips, 5-8 mm off the
real fingers on the distal links: contacts placed on them lay on no finger. Read with `prefer_visual`, such a link
takes its visual meshes (the surfaces a robot touches with, and the ones the physics test collides); links whose
collision geometry is a mesh keep it.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET

from defusedxml.ElementTree import fromstring

PRIMITIVES = ("box", "sphere", "cylinder", "capsule")


def prefer_visual(urdf: bytes) -> bytes:
    """The URDF with the collision elements dropped from every link that collides only through primitives and
    has a visual mesh (read with ``use_visual`` the link then takes its visual meshes)."""
    root = fromstring(urdf, forbid_dtd=True, forbid_entities=True, forbid_external=True)
    for link in root.findall("link"):
        cols = link.findall("collision")
        visual_mesh = any(v.find("geometry/mesh") is not None for v in link.findall("visual"))
        primitive = all(
            (g := c.find("geometry")) is not None and len(g) > 0 and all(child.tag in PRIMITIVES for child in g)
            for c in cols
        )
        if cols and visual_mesh and primitive:
            for c in cols:
                link.remove(c)
    return bytes(ET.tostring(root))
