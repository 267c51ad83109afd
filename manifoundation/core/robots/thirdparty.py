"""Third-party hands from installed PyPI packages, packed as a user would upload them (tests and benchmarks).

Nobody on the team wrote these descriptions; each is zipped from the package's own files (the description plus
every mesh file it names, paths kept), so registering one exercises exactly what a user's upload does:

- ``g1_dex3`` (example-robot-data): ``g1_description/urdf/g1_29dof_with_hand_rev_1_0.urdf``, the whole G1
  humanoid (URDF), palm ``right_hand_palm_link``;
- ``rethink`` (robosuite): ``manifoundation/core/assets/grippers/rethink_gripper.xml``, a parallel gripper (MJCF), palm
  ``gripper_base``;
- ``orca`` (orca-sim): ``scene_right.xml`` and its includes, the five-finger ORCA hand (MJCF), palm ``right_palm``;
- ``trifinger`` (robot-properties-fingers): ``urdf/pro/trifingerpro.urdf`` (URDF), palm ``base_link``.
"""

from __future__ import annotations

import io
import re
import sysconfig
import zipfile
from dataclasses import dataclass
from pathlib import Path


def _site() -> Path:
    return Path(sysconfig.get_paths()["purelib"])


@dataclass(frozen=True)
class ThirdPartyHand:
    """A packaged hand: its main description, the folder its archive paths are relative to, its palm.

    Attributes:
        name: short name.
        description: the main description file (absolute path).
        root: archive paths are relative to this folder.
        palm: the palm link / body.
        package: the PyPI package that ships it.
    """

    name: str
    description: Path
    root: Path
    palm: str
    package: str

    @property
    def available(self) -> bool:
        """Whether the package is installed."""
        return self.description.is_file()

    def files(self) -> list[Path]:
        """The description, the files it includes and every mesh file they name (the hand's own meshes
        only for the G1: the whole humanoid's are 30 MB)."""
        out, todo = [self.description], [self.description]
        while todo:
            path = todo.pop()
            text = path.read_text()
            for ref in re.findall(r'(?:file|filename)="([^"]+)"', text):
                target = self.locate(path, ref)
                if target is None or target in out or (self.name == "g1_dex3" and "right_hand" not in target.name):
                    continue
                out.append(target)
                if target.suffix.lower() in (".xml", ".mjcf"):
                    todo.append(target)
        return out

    def locate(self, referrer: Path, ref: str) -> Path | None:
        """The package file a reference in ``referrer`` names (package:// tails, relative paths), or None."""
        if ref.startswith("package://"):
            tail = ref[len("package://") :].split("/", 1)[1]
            hits = [p for p in (self.root / tail, self.root.parent / tail) if p.is_file()]
            return hits[0] if hits else None
        for base in (referrer.parent, self.description.parent, self.description.parent / "assets"):
            if (base / ref).is_file():
                return (base / ref).resolve()
        return None

    def archive(self) -> bytes:
        """A zip of :meth:`files`, paths relative to ``root``."""
        buf = io.BytesIO()
        with zipfile.ZipFile(buf, "w", zipfile.ZIP_DEFLATED) as z:
            for path in self.files():
                z.write(path, path.resolve().relative_to(self.root.resolve()).as_posix())
        return buf.getvalue()


def third_party_hands() -> dict[str, ThirdPartyHand]:
    """The hands of the module doc, by name (``available`` says whether their package is installed)."""
    sp = _site()
    erd = sp / "cmeel.prefix" / "share" / "example-robot-data" / "robots"
    orca = sp / "orca_sim"
    fingers = sp / "robot_properties_fingers"
    grippers = sp / "robosuite" / "models" / "assets" / "grippers"
    return {
        "g1_dex3": ThirdPartyHand(
            "g1_dex3", erd / "g1_description" / "urdf" / "g1_29dof_with_hand_rev_1_0.urdf", erd,
            "right_hand_palm_link", "example-robot-data",
        ),
        "rethink": ThirdPartyHand("rethink", grippers / "rethink_gripper.xml", grippers, "gripper_base", "robosuite"),
        "orca": ThirdPartyHand("orca", orca / "scene_right.xml", orca, "right_palm", "orca-sim"),
        "trifinger": ThirdPartyHand(
            "trifinger", fingers / "urdf" / "pro" / "trifingerpro.urdf", fingers, "base_link",
            "robot-properties-fingers",
        ),
    }  # fmt: skip
