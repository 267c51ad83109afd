"""The built-in hands, located and modelled by the audit itself (no code shared with the service's registry).

================  ===========================================================  ==================  ============
name              description file                                             palm                geometry
================  ===========================================================  ==================  ============
``allegro``       example-robot-data ``allegro_hand_description/urdf/``        ``palm_link``       visual†
                  ``allegro_right_hand.urdf``
``leap``          ghand ``assets/models/urdf/ghand_right.urdf``                ``root``            visual (PLY)
``shadow``        gymnasium-robotics ``envs/assets/hand/reach.xml`` (MJCF)     ``robot0:palm``     collision*
``panda_gripper`` example-robot-data ``panda_description/urdf/panda.urdf``     ``panda_hand``      collision†
``barrett``       ``manifoundation/core/robots/descriptions/barrett_bh8.urdf``              ``bh_palm``
collision ``kinova3f``      ``manifoundation/core/robots/descriptions/kinova_3f.urdf``                ``k3f_palm``
collision
================  ===========================================================  ==================  ============

"geometry" is what ``prefer="real"`` (the default) picks: per link, collision elements where the file has them,
else visual meshes, except († Allegro; the Panda's fingers) a URDF link that collides only through primitives drawn
around it: its visual meshes, the real finger (*Shadow: capsules and boxes; its knuckle bodies have visual meshes
only). The barrett and kinova3f URDFs are files of this repository (data, read as files, not imported). Fingertip
links (index, middle, ring, (little,) thumb) are the same facts as the service's; they are plain names here.
"""

from __future__ import annotations

import functools
import sysconfig
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from research.audit.geometry import LinkGeometry, mjcf_link_geometry, pose_matrix, urdf_link_geometry
from research.audit.kinematics import Kinematics, MjcfKinematics, UrdfKinematics, complete_joints

OUR_DESCRIPTIONS = Path(__file__).resolve().parents[2] / "manifoundation" / "core" / "robots" / "descriptions"


def site_packages() -> Path:
    """The interpreter's site-packages (where the hand packages install their files)."""
    return Path(sysconfig.get_paths()["purelib"])


def _erd_share() -> Path:
    return site_packages() / "cmeel.prefix" / "share"


@dataclass(frozen=True)
class HandSpec:
    """Where a built-in hand's description is and which of its links matter.

    Attributes:
        name: hand name.
        path: the description file.
        palm: palm link / body.
        fingertips: fingertip links.
    """

    name: str
    path: Path
    palm: str
    fingertips: tuple[str, ...]

    @property
    def is_mjcf(self) -> bool:
        """Whether the description is an MJCF file."""
        return self.path.suffix == ".xml"

    def resolve_mesh(self, filename: str) -> Path:
        """A URDF mesh filename → file: ``package://<pkg>/rest`` under ``cmeel.prefix/share/<pkg>``,
        relative names against the URDF's folder."""
        if filename.startswith("package://"):
            return _erd_share() / filename[len("package://") :]
        return (self.path.parent / filename).resolve()


def hand_specs() -> dict[str, HandSpec]:
    """The built-in hands' specs by name."""
    erd = _erd_share() / "example-robot-data" / "robots"
    sp = site_packages()
    fingers = ("ff", "mf", "rf", "lf", "th")
    return {
        "allegro": HandSpec(
            "allegro", erd / "allegro_hand_description" / "urdf" / "allegro_right_hand.urdf", "palm_link",
            ("link_3.0_tip", "link_7.0_tip", "link_11.0_tip", "link_15.0_tip"),
        ),
        "leap": HandSpec(
            "leap", sp / "ghand" / "assets" / "models" / "urdf" / "ghand_right.urdf", "root",
            ("tip_soft_2", "tip_soft", "tip_soft_1", "tip_soft__thumb"),
        ),
        "leap_hand": HandSpec(
            "leap_hand", OUR_DESCRIPTIONS / "leap_hand" / "right_hand.xml", "palm",
            ("if_ds", "mf_ds", "rf_ds", "th_ds"),
        ),
        "shadow": HandSpec(
            "shadow", sp / "gymnasium_robotics" / "envs" / "assets" / "hand" / "reach.xml", "robot0:palm",
            tuple(f"robot0:{f}distal" for f in fingers),
        ),
        "panda_gripper": HandSpec(
            "panda_gripper", erd / "panda_description" / "urdf" / "panda.urdf", "panda_hand",
            ("panda_leftfinger", "panda_rightfinger"),
        ),
        "barrett": HandSpec(
            "barrett", OUR_DESCRIPTIONS / "barrett_bh8.urdf", "bh_palm",
            ("bh_f1_distal", "bh_f2_distal", "bh_f3_distal"),
        ),
        "kinova3f": HandSpec(
            "kinova3f", OUR_DESCRIPTIONS / "kinova_3f.urdf", "k3f_palm",
            ("k3f_f1_distal", "k3f_f2_distal", "k3f_f3_distal"),
        ),
    }  # fmt: skip


class AuditHand:
    """A hand as the audit models it: palm-rooted FK, coupled joints, link geometry.

    Attributes:
        spec: where it comes from.
        kinematics: its forward kinematics.
        links: link → geometry (links without geometry in the chosen source are absent).
    """

    def __init__(self, spec: HandSpec, prefer: str = "real") -> None:
        """Load the description and every link's geometry.

        Args:
            spec: the hand.
            prefer: geometry source, ``"auto"``/``"collision"`` (collision where the link has it, else visual),
                ``"visual"`` (visual where the link has it, else collision) or ``"real"`` (as ``"auto"``, but a
                URDF link colliding only through primitives takes its visual meshes).
        """
        self.spec = spec
        self.kinematics: Kinematics
        self.links: dict[str, LinkGeometry] = {}
        if spec.is_mjcf:
            mk = MjcfKinematics(spec.path, spec.palm)
            self.kinematics = mk
            for b, name in zip(mk.body_ids, mk.links, strict=True):
                if (g := mjcf_link_geometry(mk.model, b, prefer)) is not None:
                    self.links[name] = g
        else:
            uk = UrdfKinematics(spec.path, spec.palm)
            self.kinematics = uk
            for name in uk.links:
                if (g := urdf_link_geometry(uk.urdf, name, spec.resolve_mesh, prefer)) is not None:
                    self.links[name] = g

    @property
    def name(self) -> str:
        """Hand name."""
        return self.spec.name

    @property
    def sources(self) -> dict[str, str]:
        """Link → geometry source (``"collision"`` / ``"visual"``)."""
        return {name: g.source for name, g in self.links.items()}

    def joint_values(
        self, names: Sequence[str], values: Sequence[float] | np.ndarray
    ) -> tuple[dict[str, float], list[str], list[str]]:
        """All movable joints from the reported ones (see :func:`research.audit.kinematics.complete_joints`).

        Returns:
            ``(values, missing, problems)``.
        """
        if len(names) != len(values):
            return {}, [], [f"{len(names)} joint names but {len(values)} values"]
        return complete_joints(self.kinematics, dict(zip(names, np.asarray(values, dtype=np.float64), strict=True)))

    def limit_violations(self, q: Mapping[str, float], tol: float = 1e-4) -> dict[str, float]:
        """Joint → amount by which it leaves its limits (only joints that do, by more than ``tol``)."""
        out = {}
        for name, (lo, hi) in self.kinematics.limits.items():
            excess = max(lo - q[name], q[name] - hi, 0.0)
            if excess > tol:
                out[name] = excess
        return out

    def link_poses(
        self, palm_position: np.ndarray, palm_quaternion: np.ndarray, q: Mapping[str, float]
    ) -> dict[str, np.ndarray]:
        """World poses of all links at or below the palm.

        Args:
            palm_position: (3,) world position of the palm frame.
            palm_quaternion: (4,) its orientation, ``(w, x, y, z)``.
            q: every movable joint's value.

        Returns:
            link → (4, 4) ``world_T_link = world_T_palm · palm_T_link(q)``.
        """
        world_T_palm = pose_matrix(palm_position, palm_quaternion)
        return {name: world_T_palm @ T for name, T in self.kinematics.palm_transforms(q).items()}


@functools.cache
def load_hand(name: str, prefer: str = "real") -> AuditHand:
    """The built-in hand ``name`` (built once per process and geometry source).

    Raises:
        KeyError: not a built-in hand (the message lists them).
    """
    specs = hand_specs()
    specs["leap_kaizen"] = specs["leap"]  # the service's name for ghand's hand ("leap" stays its alias)
    if name not in specs:
        raise KeyError(f"unknown hand {name!r}; built-in hands: {', '.join(sorted(specs))}")
    return AuditHand(specs[name], prefer)
