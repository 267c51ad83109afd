"""Our answers in DexGraspBench's format, for its own evaluation code (JYChen18/DexGraspBench, issue 63).

DexGraspBench (DGB, the benchmark of BODex) evaluates a grasp from a ``.npy`` dict: ``obj_path`` (a folder with
``info/simplified.json`` and convex pieces ``urdf/meshes/*.obj``), ``obj_scale``, ``obj_pose`` (7: x y z, w x y z)
and ``pregrasp_qpos`` / ``grasp_qpos`` / ``squeeze_qpos``: the hand's qpos in DGB's MuJoCo model, i.e. the pose of the
hand XML's world frame (a free joint welded to a mocap body, 7 values) followed by every hand joint in model order.
This module turns one of our answers (palm pose wxyz in the object frame, free joint values by our names, the
pregrasp / grasp / squeeze targets our physics test used) into that: the root pose is the palm pose times the inverse
of the DGB palm body's fixed pose in its XML (`DgbHand.palm_in_root`), joint values go by name with the axis sign
(`DgbHand.joints`; tied joints such as Shadow's J0 get their tied values), and the object's convex pieces (the ones
our test collided, `manifoundation.core.physics.ObjectShape`) become DGB's object folder, centred at the pieces'
centre like our test's object body, with a density that gives DGB's 0.1 kg.

The object is placed at `RESET_GUARD` (not at the world origin): MuJoCo answers a diverged step by resetting the
state to the model's initial one, which puts DGB's object at the origin; placed elsewhere, such a reset moves it by
``|RESET_GUARD|`` and DGB's own 5 cm criterion fails it (at the origin it would read as held).

The hand joint order and qpos addresses are DGB's model's business: the job lists values by DGB joint name and the
driver (``research/benchmarks/dexgraspbench/dgb_driver.py``, run in DGB's venv) places them.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import trimesh

if TYPE_CHECKING:
    from manifoundation.core.physics import ObjectShape
    from manifoundation.core.robots.hand import Hand

DGB_COMMIT = "1e7a5a6fce27cc92911080cbdc5ce9da56fddbf0"
"""The DexGraspBench commit the mapping was made and checked against (2025-06-05, "update README")."""
RESET_GUARD = np.array([0.5, 0.0, 0.0])
"""Where the object's centre is put in DGB's world (m); see the module doc."""
SQRT_HALF = float(np.sqrt(0.5))


@dataclass(frozen=True)
class DgbHand:
    """One of our hands as DGB's hand.

    Attributes:
        config: DGB's hand config (``config/hand/<config>.yaml``).
        palm_in_root: our palm frame in DGB's hand XML world frame: position (3,), quaternion wxyz (4,); our palm
            frame is the frame of DGB's palm body (checked by forward kinematics, tests and `fk_bodies`).
        joints: our moving joint -> (DGB joint, sign): DGB value = sign × ours.
        bodies: our link -> DGB body whose frame origin is the same point of the hand (for FK checks).
    """

    config: str
    palm_in_root: tuple[tuple[float, float, float], tuple[float, float, float, float]]
    joints: dict[str, tuple[str, float]]
    bodies: dict[str, str] = field(default_factory=dict)


def _allegro() -> DgbHand:
    fingers = (("ff", 0), ("mf", 4), ("rf", 8), ("th", 12))
    parts = ("base", "proximal", "medial", "distal")
    joints = {f"joint_{base + k}.0": (f"{f}j{k}", 1.0) for f, base in fingers for k in range(4)}
    bodies = {f"link_{base + k}.0": f"{f}_{parts[k]}" for f, base in fingers for k in range(4)}
    # Menagerie's palm body is the URDF's palm_link turned by quat (0, 1, 0, 1)/√2 (DGB's convert_format says so too)
    return DgbHand("allegro", ((0.0, 0.0, 0.0), (0.0, SQRT_HALF, 0.0, SQRT_HALF)), joints, bodies)


def _leap_hand() -> DgbHand:
    names = [f"{f}_{j}" for f in ("if", "mf", "rf") for j in ("mcp", "rot", "pip", "dip")]
    names += ["th_cmc", "th_axl", "th_mcp", "th_ipl"]
    links = [f"{f}_{b}" for f in ("if", "mf", "rf") for b in ("bs", "px", "md", "ds")] + ["th_mp", "th_bs", "th_px"]
    # our leap_hand is Menagerie's tree: same names; its palm body sits at (0, 0, 0.1) turned by quat (0, 1, 0, 0)
    return DgbHand(
        "leap", ((0.0, 0.0, 0.1), (0.0, 1.0, 0.0, 0.0)), {n: (n, 1.0) for n in names},
        {b: b for b in [*links, "th_ds"]},
    )  # fmt: skip


def _shadow() -> DgbHand:
    # gymnasium-robotics' Shadow (ours) numbers a finger's joints from 0 at the tip, Menagerie's (DGB) from 1; the
    # first and middle fingers' abduction and the thumb's two distal joints turn about opposite axes
    flip = {"robot0:FFJ3", "robot0:MFJ3", "robot0:THJ0", "robot0:THJ1"}
    ours = [f"robot0:{f}J{k}" for f in ("FF", "MF", "RF") for k in range(4)]
    ours += [f"robot0:LFJ{k}" for k in range(5)] + [f"robot0:THJ{k}" for k in range(5)]
    joints = {n: (f"rh_{n[7:10]}{int(n[10:]) + 1}", -1.0 if n in flip else 1.0) for n in ours}
    links = [f"{f}{p}" for f in ("ff", "mf", "rf", "lf") for p in ("knuckle", "proximal", "middle", "distal")]
    links += ["thbase", "thproximal", "thhub", "thmiddle", "thdistal"]  # lfmetacarpal: its frames differ by 28 mm
    # our palm frame is DGB's rh_palm, which DGB's XML (forearm and wrist removed) puts 34 mm up its world z
    return DgbHand(
        "shadow", ((0.0, 0.0, 0.034), (1.0, 0.0, 0.0, 0.0)), joints, {f"robot0:{b}": f"rh_{b}" for b in links}
    )


HANDS: dict[str, DgbHand] = {"leap_hand": _leap_hand(), "allegro": _allegro(), "shadow": _shadow()}
"""Our hands that DGB has (DGB's ``leap`` is the original LEAP Hand: ours is ``leap_hand``, not ``leap``)."""


def dgb_hand(name: str) -> DgbHand:
    """The mapping of our hand ``name``.

    Raises:
        KeyError: a hand DGB does not have (LEAP KAIZEN ``leap``, the grippers, user hands).
    """
    if name not in HANDS:
        raise KeyError(f"hand {name!r} has no DexGraspBench counterpart (those that do: {', '.join(HANDS)})")
    return HANDS[name]


def _matrix(quat: np.ndarray) -> np.ndarray:
    w, x, y, z = np.asarray(quat, float) / np.linalg.norm(quat)
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ])  # fmt: skip


def _quat(R: np.ndarray) -> np.ndarray:
    """(3, 3) -> wxyz with w ≥ 0 (Shepperd)."""
    t = float(np.trace(R))
    if t > 0:
        s = 2.0 * np.sqrt(t + 1.0)
        q = np.array([0.25 * s, (R[2, 1] - R[1, 2]) / s, (R[0, 2] - R[2, 0]) / s, (R[1, 0] - R[0, 1]) / s])
    else:
        i = int(np.argmax(np.diag(R)))
        j, k = (i + 1) % 3, (i + 2) % 3
        s = 2.0 * np.sqrt(1.0 + R[i, i] - R[j, j] - R[k, k])
        q = np.zeros(4)
        q[0] = (R[k, j] - R[j, k]) / s
        q[1 + i] = 0.25 * s
        q[1 + j] = (R[j, i] + R[i, j]) / s
        q[1 + k] = (R[k, i] + R[i, k]) / s
    return q if q[0] >= 0 else -q


def root_pose(hand: DgbHand, palm_position: np.ndarray, palm_quaternion: np.ndarray) -> np.ndarray:
    """(7,) DGB's hand root pose (x y z w x y z) for our palm pose (wxyz), in the same frame."""
    R_palm = _matrix(palm_quaternion)
    R_rp = _matrix(np.array(hand.palm_in_root[1]))
    R = R_palm @ R_rp.T
    t = np.asarray(palm_position, float) - R @ np.array(hand.palm_in_root[0])
    return np.concatenate([t, _quat(R)])


def moving_joint_values(hand: Hand, q: np.ndarray) -> dict[str, float]:
    """Every moving joint of ``hand`` below its palm (tied ones included) for its free joint values q (D,)."""
    from manifoundation.core.physics.visual import physics_description

    index = {n: i for i, n in enumerate(hand.joint_names)}
    out = {}
    for j in physics_description(hand).joints:
        if j.type == "fixed":
            continue
        src, mult, off = j.mimic if j.mimic is not None else (j.name, 1.0, 0.0)
        out[j.name] = mult * float(q[index[src]]) + off
    return out


def dgb_joint_values(hand: DgbHand, moving: dict[str, float]) -> dict[str, float]:
    """DGB joint name -> value for our moving joints' values.

    Raises:
        KeyError: a joint of ours the mapping lacks.
    """
    return {hand.joints[n][0]: hand.joints[n][1] * v for n, v in moving.items()}


def write_object(shape: ObjectShape, folder: Path, mass: float = 0.1) -> np.ndarray:
    """Write ``shape`` as DGB's object folder (each piece's convex hull, centred at ``shape.centre``) and return that
    centre (3,) in the object's frame. ``info/simplified.json`` makes DGB's density rule give ``mass`` (DGB sets
    ``obj_mass / (mass / density / scale³ × obj_scale³)``; with scale 1, density 1 and ``mass`` = the pieces' total
    volume it is ``obj_mass`` over that volume)."""
    centre = shape.centre
    meshes = folder / "urdf" / "meshes"
    meshes.mkdir(parents=True, exist_ok=True)
    volume = 0.0
    for i, piece in enumerate(shape.pieces):
        hull = trimesh.convex.convex_hull(np.asarray(piece, float) - centre)
        hull.export(meshes / f"convex_piece_{i:03d}.obj")
        volume += float(hull.volume)
    (folder / "info").mkdir(exist_ok=True)
    info = {"mass": volume, "density": 1.0, "scale": 1.0, "note": f"pieces of our physics test, {mass} kg in DGB"}
    (folder / "info" / "simplified.json").write_text(json.dumps(info))
    return np.asarray(centre)


def convert_answer(hand: Hand, record: dict[str, Any], centre: np.ndarray, obj_dir: Path) -> dict[str, Any]:
    """One DGB job entry for a record of `mani-lab eval physics --json` (its palm pose, joints by name and the
    pregrasp / grasp / squeeze targets), the object folder written by `write_object` and its centre.

    Returns:
        ``{"obj_path", "obj_scale", "obj_pose" (7), "root" (7), "pregrasp" / "grasp" / "squeeze": {DGB joint: value}}``
        with the object at `RESET_GUARD` and the hand in DGB's world frame (``"shift"``: object frame -> that frame).
    """
    mapping = dgb_hand(record["hand"])
    names = list(record["joints"])
    if names != list(hand.joint_names):
        raise ValueError(f"record joints {names} are not hand {hand.name!r}'s {list(hand.joint_names)}")
    shift = RESET_GUARD - np.asarray(centre, float)  # object frame -> DGB world
    root = root_pose(mapping, np.asarray(record["palm_position"]) + shift, np.asarray(record["palm_quaternion"]))
    out: dict[str, Any] = {
        "obj_path": str(obj_dir), "obj_scale": 1.0, "obj_pose": [*RESET_GUARD.tolist(), 1.0, 0.0, 0.0, 0.0],
        "root": root.tolist(), "shift": shift.tolist(),
    }  # fmt: skip
    for stage in ("pregrasp", "grasp", "squeeze"):
        out[stage] = dgb_joint_values(mapping, moving_joint_values(hand, np.asarray(record[stage], float)))
    return out
