"""The hand registry: built-in hands by name (cached) and hardened loading of a user's URDF.

Built-ins and their palm frames (``approach_axis`` is the palm-frame direction the palm faces / fingers close
towards; rest poses have the fingers open and slightly flexed, thumbs opposing):

================  ==========================================  ========  ===============================================
name              source                                      free DoF  palm frame (link), fingers, approach
================  ==========================================  ========  ===============================================
``allegro``       example-robot-data ``allegro_right_hand``   16        ``palm_link``: fingers along +z, approach +x
``leap_hand``     our ``descriptions/leap_hand/`` (the        16        ``palm`` (the LEAP Hand's palm body); approach
                  original LEAP Hand, MIT: see its LICENSE)             towards the fingertips at rest
``leap_kaizen``   ghand ``ghand_right.urdf`` ("LEAP V1        16        ``root``: fingers along +x, approach −z
                  KAIZEN", a LEAP-style redesign)
``shadow``        gymnasium-robotics ``hand/reach.xml``       18 (22)   ``robot0:palm``: fingers along +z, approach −y
``panda_gripper`` example-robot-data ``panda.urdf`` (hand)    1 (2)     ``panda_hand``: fingers along +z, approach +z
``barrett``       our ``descriptions/barrett_bh8.urdf``       4 (7)     ``bh_palm``: fingers along +z, approach +z
``kinova3f``      our ``descriptions/kinova_3f.urdf``         3 (6)     ``k3f_palm``: fingers along +z, approach +z
================  ==========================================  ========  ===============================================

``leap`` is an alias of ``leap_kaizen`` (what it named before the original LEAP Hand was offered): its joint values
are ghand's (flexion −1.75..0.31 rad), not a LEAP Hand's. ``leap_hand`` is the original LEAP Hand (MCP flexion
−0.314..2.23 rad, the LEAP Hand's joint names ``if_mcp``, ``if_rot``, ...): joint values mean what they mean on a
real LEAP Hand. It is built from its MJCF and fingertip meshes with the same procedure as a user's hand
(:mod:`manifoundation.core.robots.user_hand`).

Fingertips are listed index, middle, ring, (little,) thumb. Numbers in parentheses count the moving joints
before tying: Shadow's distal joints J0 follow J1 through the MJCF's coupling tendon (J0 = 0.00805/0.00705 · J1),
the Panda's second finger mimics the first, the Barrett spread is shared by fingers 1 and 2 and its distal joints
are coupled to the proximal ones, as are the Kinova ones (see the URDFs).
"""

from __future__ import annotations

import functools
import io
import os
import sysconfig
import zipfile
from collections.abc import Callable
from pathlib import Path

import numpy as np
import trimesh

from manifoundation.core.errors import HandLoadError, UnknownHand
from manifoundation.core.robots.description import RobotDescription
from manifoundation.core.robots.hand import Hand
from manifoundation.core.robots.meshcache import hull_loader
from manifoundation.core.robots.mjcf import parse_mjcf
from manifoundation.core.robots.real_surfaces import prefer_visual
from manifoundation.core.robots.urdf import MAX_URDF_BYTES, MeshLoader, parse_urdf
from manifoundation.core.robots.user_hand import HandSource, build_user_hand

DESCRIPTIONS = Path(__file__).parent / "descriptions"


def _site_packages() -> Path:
    return Path(sysconfig.get_paths()["purelib"])


def _erd(*parts: str) -> Path:
    return _site_packages() / "cmeel.prefix" / "share" / "example-robot-data" / "robots" / Path(*parts)


def _package_loader(urdf_dir: Path, package_root: Path) -> MeshLoader:
    """Resolve ``package://<pkg>/...`` against ``package_root`` and relative paths against ``urdf_dir``;
    refuses anything that leaves those directories (built-ins only)."""
    roots = [urdf_dir.resolve(), package_root.resolve()]

    def load(filename: str, scale: np.ndarray) -> trimesh.Trimesh | None:
        if filename.startswith("package://"):
            rel = filename[len("package://") :].split("/", 1)[1]
            path = (package_root / rel).resolve()
        else:
            path = (urdf_dir / filename).resolve()
        if not any(str(path).startswith(str(r) + os.sep) for r in roots):
            raise HandLoadError(f"mesh path {filename!r} leaves the package directory")
        mesh = trimesh.load(str(path), force="mesh")
        assert isinstance(mesh, trimesh.Trimesh)
        # a COLLADA file's triangles come apart (each corner its own vertex, for its normal and texture: the
        # Panda's finger read as 564 pieces): welded, the surface's connected parts are the real ones
        mesh.merge_vertices(merge_tex=True, merge_norm=True)
        mesh.apply_scale(scale)
        return mesh

    return load


def _allegro() -> Hand:
    desc = _real_surfaces("allegro")
    tips = ["link_3.0_tip", "link_7.0_tip", "link_11.0_tip", "link_15.0_tip"]
    # tip spheres (r = 12 mm) sit on the tip link origins: contact on the pad side (+x after flexion about y)
    offsets = np.tile([0.012 * np.sqrt(0.5), 0.0, 0.012 * np.sqrt(0.5)], (4, 1))
    rest = np.array([0.0, 0.3, 0.3, 0.3] * 3 + [1.3, 0.37, 0.95, 0.0])  # thumb opposing the fingers
    return Hand(desc, name="allegro", fingertips=tips, tip_offsets=offsets, rest=rest, approach_axis=[1.0, 0, 0])


def _panda_gripper() -> Hand:
    desc = _real_surfaces("panda_gripper")
    # rubber pads: centred 45.25 mm up the finger, inner face on the finger plane
    offsets = np.array([[0.0, 0.0, 0.04525], [0.0, 0.0, 0.04525]])
    return Hand(
        desc, name="panda_gripper", palm="panda_hand", fingertips=["panda_leftfinger", "panda_rightfinger"],
        tip_offsets=offsets, rest=np.array([0.04]), approach_axis=[0, 0, 1.0],
    )  # fmt: skip


def _leap() -> Hand:
    path = _site_packages() / "ghand" / "assets" / "models" / "urdf" / "ghand_right.urdf"
    # the URDF has visual meshes only: each mesh file is replaced by its cached convex hull (meshcache.py)
    desc = parse_urdf(path.read_bytes(), mesh_loader=hull_loader(DESCRIPTIONS / "leap_hulls.npz"), use_visual=True)
    # fingers (joints: MCP flexion, abduction, PIP, DIP): index tip_soft_2 (id1, id0, id2, id3), middle tip_soft
    # (id9, id8, id10, id11), ring tip_soft_1 (id5, id4, id6, id7); thumb id12..id15
    tips = ["tip_soft_2", "tip_soft", "tip_soft_1", "tip_soft__thumb"]
    # pad points of the soft tips (link y runs along the finger, the pad bulges towards link +x; thumb -x)
    offsets = np.array([[0.017, 0.025, 0.0]] * 3 + [[-0.0155, 0.026, 0.0]])
    # palm frame = URDF root: fingers along +x, flexion (negative joint values) curls them towards -z
    rest = {"id9": -0.4, "id10": -0.4, "id11": -0.3, "id5": -0.4, "id6": -0.4, "id7": -0.3, "id1": -0.4}
    rest |= {"id2": -0.4, "id3": -0.3, "id12": -1.5, "id13": -0.18, "id14": -1.4, "id15": 0.3}
    return Hand(
        desc, name="leap_kaizen", fingertips=tips, tip_offsets=offsets, rest=rest, approach_axis=[0.0, 0.0, -1.0]
    )


def _leap_hand() -> Hand:
    folder = DESCRIPTIONS / "leap_hand"
    files = {name: (folder / name).read_bytes() for name in ("right_hand.xml", "tip.obj", "thumb_tip.obj")}
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w") as z:
        for name, data in files.items():
            z.writestr(name, data)
    # fingertips: the distal bodies (leaves) if_ds, mf_ds, rf_ds, th_ds; tips at their distal ends
    return build_user_hand(HandSource(name="leap_hand", archive=buf.getvalue(), palm="palm")).hand


def _shadow() -> Hand:
    path = _site_packages() / "gymnasium_robotics" / "envs" / "assets" / "hand" / "reach.xml"
    desc = parse_mjcf(str(path), name="shadow")
    fingers = ["ff", "mf", "rf", "lf"]
    tips = [f"robot0:{f}distal" for f in fingers] + ["robot0:thdistal"]
    # distal capsules end 31 mm up the link; pads face the flexion side (-y for the fingers, thumb: see MJCF)
    offsets = np.array([[0.0, -0.006, 0.022]] * 4 + [[-0.008, 0.0, 0.022]])
    rest = {f"robot0:{f.upper()}J{k}": v for f in fingers for k, v in ((3, 0.0), (2, 0.3), (1, 0.3))}
    rest |= {"robot0:THJ4": 0.95, "robot0:THJ3": 1.0, "robot0:THJ2": 0.07, "robot0:THJ1": 0.35}  # opposing
    return Hand(
        desc, name="shadow", palm="robot0:palm", fingertips=tips, tip_offsets=offsets, rest=rest,
        approach_axis=[0.0, -1.0, 0.0],
    )  # fmt: skip


def _barrett() -> Hand:
    desc = parse_urdf((DESCRIPTIONS / "barrett_bh8.urdf").read_bytes())
    tips = ["bh_f1_distal", "bh_f2_distal", "bh_f3_distal"]
    offsets = np.array([[0.0, -0.009, 0.045]] * 3)  # pads: flexion side of the distal links, near the tip
    rest = {"bh_j11": 0.0, "bh_j12": 0.05, "bh_j22": 0.05, "bh_j32": 0.05}
    return Hand(desc, name="barrett", fingertips=tips, tip_offsets=offsets, rest=rest, approach_axis=[0, 0, 1.0])


def _kinova3f() -> Hand:
    desc = parse_urdf((DESCRIPTIONS / "kinova_3f.urdf").read_bytes())
    tips = ["k3f_f1_distal", "k3f_f2_distal", "k3f_f3_distal"]
    offsets = np.array([[0.0, -0.005, 0.036]] * 3)
    rest = {"k3f_j11": 0.1, "k3f_j21": 0.1, "k3f_j31": 0.1}
    return Hand(desc, name="kinova3f", fingertips=tips, tip_offsets=offsets, rest=rest, approach_axis=[0, 0, 1.0])


def real_surface_description(name: str) -> RobotDescription | None:
    """A URDF built-in (`urdf_source`) read from its real surfaces: links that collide only through primitives drawn
    around them (Allegro's boxes and 12 mm tip spheres, 5-8 mm off its distal links; the Panda's finger boxes) take
    their visual meshes (`manifoundation.core.robots.real_surfaces`); None for the other hands. The hand is built
    from it, and the physics test reads it (`manifoundation.core.physics.visual`)."""
    source = urdf_source(name)
    if source is None:
        return None
    data, loader = source
    return parse_urdf(prefer_visual(data), mesh_loader=loader, use_visual=True)


def _real_surfaces(name: str) -> RobotDescription:
    desc = real_surface_description(name)
    assert desc is not None, name
    return desc


def urdf_source(name: str) -> tuple[bytes, MeshLoader] | None:
    """The URDF document and its mesh loader of a built-in hand described by a URDF with mesh files (the hand is
    built from its real surfaces in it, `_real_surfaces`); None for the other hands."""
    name = ALIASES.get(name, name)
    if name == "allegro":
        path = _erd("allegro_hand_description", "urdf", "allegro_right_hand.urdf")
    elif name == "panda_gripper":
        path = _erd("panda_description", "urdf", "panda.urdf")
    else:
        return None
    return path.read_bytes(), _package_loader(path.parent, _erd().parent)


BUILTINS: dict[str, Callable[[], Hand]] = {
    "allegro": _allegro,
    "panda_gripper": _panda_gripper,
    "leap_hand": _leap_hand,
    "leap_kaizen": _leap,
    "shadow": _shadow,
    "barrett": _barrett,
    "kinova3f": _kinova3f,
}


ALIASES: dict[str, str] = {"leap": "leap_kaizen"}
"""Old names still accepted: alias -> built-in name."""


def list_hands(*, aliases: bool = False) -> list[str]:
    """Names of the built-in hands (with ``aliases``: and their old names, ``ALIASES``)."""
    return sorted([*BUILTINS, *(ALIASES if aliases else ())])


@functools.cache
def get_hand(name: str) -> Hand:
    """The built-in hand ``name`` (built once per process).

    Raises:
        UnknownHand: ``name`` is not a built-in (the message lists them).
    """
    if name in ALIASES:
        return get_hand(ALIASES[name])
    if name not in BUILTINS:
        raise UnknownHand(f"unknown hand {name!r}; built-in hands: {', '.join(list_hands(aliases=True))}")
    return BUILTINS[name]()


def load_hand(
    urdf: bytes,
    fingertips: list[str],
    tip_offsets: np.ndarray | list[list[float]] | None = None,
    name: str = "custom",
    *,
    palm: str | None = None,
    rest: np.ndarray | list[float] | None = None,
    approach_axis: np.ndarray | list[float] | None = None,
    max_bytes: int = MAX_URDF_BYTES,
) -> Hand:
    """A hand from a user's (untrusted) URDF: hardened parse, mesh filenames ignored (primitives only).

    Args:
        urdf: the URDF document (bytes).
        fingertips: fingertip link names (must exist below the palm).
        tip_offsets: (m, 3) contact points in the fingertip link frames (default zeros).
        name: the hand's name.
        palm: palm link (default: the URDF root).
        rest: (D,) rest joint values (default: 0 clipped into the limits).
        approach_axis: (3,) palm-frame approach direction (default +z).
        max_bytes: size cap.

    Raises:
        HandLoadError: unsafe, oversized, malformed or inconsistent input (the message says what).
    """
    desc = parse_urdf(urdf, mesh_loader=None, max_bytes=max_bytes)
    return Hand(
        desc,
        name=name,
        fingertips=list(fingertips),
        tip_offsets=None if tip_offsets is None else np.asarray(tip_offsets, dtype=np.float64),
        palm=palm,
        rest=None if rest is None else np.asarray(rest, dtype=np.float64),
        approach_axis=None if approach_axis is None else np.asarray(approach_axis, dtype=np.float64),
    )
