"""Test objects: meshes that installed third-party packages ship, and concave shapes built here.

:func:`third_party_objects` loads object meshes shipped by packages nobody on this team wrote (gymnasium-robotics'
kitchen assets, its hand-manipulation objects, ShadowHand and Fetch link meshes, an Adroit mesh, a TIAGo part,
robosuite's object meshes), in the fixed order of :data:`CANDIDATES` (the first 18 are the original set: the
benchmarks' and tests' first N are unchanged). Each is made watertight the simple way: vertices merged, split
into connected components, the largest watertight component kept (files without one are skipped); then it is
centred (bounding-box centre at the origin) and scaled uniformly so that its largest bounding-box extent is
``size`` (default 8 cm, within the graspable 4–12 cm). The gymnasium hand-manipulation objects (egg, block, pen)
are MJCF primitives: they are tessellated from the ``<geom name="object">`` of their XML.

:func:`concave_test_shapes` are NOT third-party: a cup with a handle, a mug, a torus and an L-shaped part, built
from tessellations without booleans (none is installed). Each is watertight; the handles are separate
watertight bodies 0.3 mm off the wall (disjoint components keep inside tests exact).
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import trimesh

from research.audit.geometry import primitive, stack_meshes
from research.audit.hands import site_packages

_KITCHEN = "gymnasium_robotics/envs/assets/kitchen_franka/kitchen_assets/meshes"
_HAND = "gymnasium_robotics/envs/assets/hand"
_STLS = "gymnasium_robotics/envs/assets/stls"
_ROBOSUITE = "robosuite/models/assets/objects/meshes"
CANDIDATES: tuple[tuple[str, str], ...] = (
    ("kettle_handle", f"{_KITCHEN}/kettlehandle.stl"),
    ("micro_handle", f"{_KITCHEN}/microhandle.stl"),
    ("oven_handle", f"{_KITCHEN}/ovenhandle.stl"),
    ("cabinet_drawer", f"{_KITCHEN}/cabinetdrawer.stl"),
    ("kettle", f"{_KITCHEN}/kettle.stl"),
    ("egg", f"{_HAND}/manipulate_egg.xml"),
    ("block", f"{_HAND}/manipulate_block.xml"),
    ("pen", f"{_HAND}/manipulate_pen.xml"),
    ("hinge_cabinet", f"{_KITCHEN}/hingecabinet.stl"),
    ("slide_cabinet", f"{_KITCHEN}/slidecabinet.stl"),
    ("light_switch_base", f"{_KITCHEN}/lightswitchbase.stl"),
    ("micro_button", f"{_KITCHEN}/microbutton.stl"),
    ("hood", f"{_KITCHEN}/hood.stl"),
    ("microwave", f"{_KITCHEN}/micro.stl"),
    ("handle_bar", f"{_KITCHEN}/handle2.stl"),
    ("burner_plate", f"{_KITCHEN}/burnerplate.stl"),
    ("adroit_distal_ellipsoid", "gymnasium_robotics/envs/assets/adroit_hand/resources/meshes/distal_ellipsoid.stl"),
    ("tiago_antenna", "cmeel.prefix/share/example-robot-data/robots/tiago_description/meshes/pmb2/objects/antenna.stl"),
    ("knob", f"{_KITCHEN}/knob.stl"),  # not watertight in any component: skipped
    ("light_switch", f"{_KITCHEN}/lightswitch.stl"),  # idem
    # robosuite's object meshes (MIT)
    ("bread", f"{_ROBOSUITE}/bread.stl"),
    ("cereal_box", f"{_ROBOSUITE}/cereal.stl"),
    ("lemon", f"{_ROBOSUITE}/lemon.stl"),
    ("milk_carton", f"{_ROBOSUITE}/milk.stl"),
    # more of gymnasium-robotics' kitchen (MIT), its ShadowHand link meshes (Apache 2.0) and its Fetch's links
    ("cabinet_base", f"{_KITCHEN}/cabinetbase.stl"),
    ("hinge_handle", f"{_KITCHEN}/hingehandle.stl"),
    ("oven", f"{_KITCHEN}/oven.stl"),
    *((f"shadow_{name.lower()}", f"{_STLS}/hand/{name}.stl")
      for name in ("F1", "F2", "F3", "TH1_z", "TH2_z", "TH3_z", "knuckle", "lfmetacarpal")),
    *((f"fetch_{name}", f"{_STLS}/fetch/{name}_link_collision.stl")
      for name in ("elbow_flex", "forearm_roll", "head_pan", "head_tilt", "shoulder_lift", "shoulder_pan",
                   "upperarm_roll", "wrist_flex", "wrist_roll")),
    ("fetch_gripper", f"{_STLS}/fetch/gripper_link.stl"),
)
"""(name, path under site-packages) of the candidate third-party objects, in the order they are returned."""


@dataclass
class ThirdPartyObject:
    """A third-party object mesh, normalised.

    Attributes:
        name: short name.
        path: the source file.
        mesh: watertight, centred, scaled mesh (m).
        scale: the uniform scale applied to the file's units.
        dropped_components: connected components of the file not kept.
        solidity: volume / convex hull volume (< 1: non-convex).
    """

    name: str
    path: Path
    mesh: trimesh.Trimesh
    scale: float
    dropped_components: int
    solidity: float

    def sample(self, count: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
        """Surface points and normals, see :func:`sample_surface`."""
        return sample_surface(self.mesh, count, seed)


def sample_surface(mesh: trimesh.Trimesh, count: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Area-uniform surface samples with their (outward) face normals.

    Args:
        mesh: the mesh.
        count: number of samples.
        seed: random seed.

    Returns:
        ``(points, normals)``, each (count, 3).
    """
    points, faces = trimesh.sample.sample_surface(mesh, count, seed=seed)
    return np.asarray(points), np.asarray(mesh.face_normals)[faces]


def _mjcf_object(path: Path) -> trimesh.Trimesh:
    geom = next(g for g in ET.parse(path).getroot().iter("geom") if g.get("name") == "object")
    size = np.array([float(v) for v in geom.get("size", "").split()])
    kind = geom.get("type", "sphere")
    if kind == "box":
        return primitive("box", 2 * size)
    if kind in ("capsule", "cylinder"):
        return primitive(kind, np.array([size[0], 2 * size[1]]))
    return primitive(kind, size)


def _normalise(mesh: trimesh.Trimesh, size: float) -> tuple[trimesh.Trimesh, float]:
    mesh = mesh.copy()
    mesh.apply_translation(-mesh.bounds.mean(axis=0))
    scale = size / float(mesh.extents.max())
    mesh.apply_scale(scale)
    return mesh, scale


def load_third_party(name: str, path: Path, size: float = 0.08) -> ThirdPartyObject | None:
    """One candidate file as a normalised object (``None`` when it has no watertight component)."""
    if path.suffix == ".xml":
        mesh, dropped = _mjcf_object(path), 0
    else:
        raw = trimesh.load(str(path), force="mesh")
        if not isinstance(raw, trimesh.Trimesh):
            return None
        raw.merge_vertices()
        parts = raw.split(only_watertight=False)
        solid = [p for p in parts if p.is_watertight and abs(p.volume) > 0]
        if not solid:
            return None
        mesh = max(solid, key=lambda p: abs(p.volume))
        dropped = len(parts) - 1
        if mesh.volume < 0:
            mesh.invert()
    mesh, scale = _normalise(mesh, size)
    return ThirdPartyObject(name, path, mesh, scale, dropped, float(mesh.volume / mesh.convex_hull.volume))


def third_party_objects(max_count: int | None = None, size: float = 0.08) -> list[ThirdPartyObject]:
    """The installed third-party objects that load as watertight meshes, in :data:`CANDIDATES` order.

    Args:
        max_count: at most this many (all when ``None``).
        size: largest extent after scaling (m).

    Returns:
        The objects (candidates whose files are absent or have no watertight component are skipped).
    """
    out: list[ThirdPartyObject] = []
    for name, rel in CANDIDATES:
        if max_count is not None and len(out) >= max_count:
            break
        path = site_packages() / rel
        if path.exists() and (obj := load_third_party(name, path, size)) is not None:
            out.append(obj)
    return out


def _arc_tube(arc_radius: float, tube_radius: float, sections: int = 48, rings: int = 24) -> trimesh.Trimesh:
    """A half-ring tube in the xz-plane bulging to +x, its flat end caps in the plane x = 0 at z = ±arc_radius."""
    phi = np.linspace(-np.pi / 2, np.pi / 2, sections + 1)
    psi = 2 * np.pi * np.arange(rings) / rings
    u = np.stack([np.cos(phi), np.zeros_like(phi), np.sin(phi)], axis=1)  # (S, 3) radial directions
    v = np.array([0.0, 1.0, 0.0])
    centre = arc_radius * u
    ring = centre[:, None] + tube_radius * (np.cos(psi)[None, :, None] * u[:, None] + np.sin(psi)[None, :, None] * v)
    verts = np.concatenate([ring.reshape(-1, 3), centre[[0, -1]]])
    faces = []
    for s in range(sections):
        for r in range(rings):
            a, b = s * rings + r, s * rings + (r + 1) % rings
            faces += [[a, b, b + rings], [a, b + rings, a + rings]]
    first, last = len(verts) - 2, len(verts) - 1
    for r in range(rings):
        faces += [[first, (r + 1) % rings, r], [last, sections * rings + r, sections * rings + (r + 1) % rings]]
    mesh = trimesh.Trimesh(verts, np.array(faces), process=False)
    if mesh.volume < 0:
        mesh.invert()
    return mesh


def _cup(
    radius: float, height: float, wall: float, bottom: float, handle: tuple[float, float] | None
) -> trimesh.Trimesh:
    profile = np.array(
        [[0, 0], [radius, 0], [radius, height], [radius - wall, height], [radius - wall, bottom], [0, bottom]]
    )
    cup = trimesh.creation.revolve(profile / radius, sections=96)  # unit scale: see geometry.primitive
    cup.apply_scale(radius)
    if handle is not None:
        arc, tube = handle
        h = _arc_tube(arc / radius, tube / radius)
        h.apply_scale(radius)
        h.apply_translation([radius + 3e-4, 0.0, height / 2])
        cup = stack_meshes([cup, h])
    cup.apply_translation(-cup.bounds.mean(axis=0))
    return cup


def _l_shape(long: float, short: float, thickness: float, depth: float) -> trimesh.Trimesh:
    poly = np.array([[0, 0], [long, 0], [long, thickness], [thickness, thickness], [thickness, short], [0, short]])
    n = len(poly)
    verts = np.concatenate([np.c_[poly, np.zeros(n)], np.c_[poly, np.full(n, depth)]])
    caps = [[0, 1, 2], [0, 2, 3], [0, 3, 4], [0, 4, 5]]
    faces = [[c, b, a] for a, b, c in caps] + [[a + n, b + n, c + n] for a, b, c in caps]
    for i in range(n):
        j = (i + 1) % n
        faces += [[i, j, j + n], [i, j + n, i + n]]
    mesh = trimesh.Trimesh(verts, np.array(faces), process=False)
    if mesh.volume < 0:
        mesh.invert()
    mesh.apply_translation(-mesh.bounds.mean(axis=0))
    return mesh


def concave_test_shapes() -> dict[str, trimesh.Trimesh]:
    """Non-convex watertight test shapes made here (not third-party), centred, 6–10 cm.

    Returns:
        ``cup_with_handle`` (r 3.5 cm, 9 cm tall, 4 mm wall, ring handle), ``mug`` (r 4 cm, 8 cm tall, 6 mm
        wall, thicker handle), ``torus`` (major 3 cm, minor 1 cm), ``l_shape`` (8 × 6 cm, 2 cm thick, 3 cm deep).
    """
    torus = trimesh.creation.torus(1.0, 1.0 / 3.0, major_sections=64, minor_sections=32)
    torus.apply_scale(0.03)
    return {
        "cup_with_handle": _cup(0.035, 0.09, 0.004, 0.006, (0.025, 0.005)),
        "mug": _cup(0.04, 0.08, 0.006, 0.008, (0.022, 0.008)),
        "torus": torus,
        "l_shape": _l_shape(0.08, 0.06, 0.02, 0.03),
    }
