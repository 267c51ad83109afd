"""Write MuJoCo Menagerie's ``leap_hand/right_hand.xml`` where a DexGraspBench copy lacks it (its submodule absent).

DexGraspBench's ``assets/hand/leap/right_hand.xml`` includes ``third_party/mujoco_menagerie/leap_hand/right_hand.xml``
(its meshes come from DexGraspBench's own ``simplified_assets``). A clone with ``git submodule update --init`` has
that file: use it. Without it, this script rebuilds its physics from two sources: the body tree, joints, limits and
collision geometry from our copy (``manifoundation/core/robots/descriptions/leap_hand/right_hand.xml``, taken from
Menagerie's file; MIT, see the LICENSE there) and Menagerie's inertials, defaults (geom solref / solimp / friction,
position kp 3 kv 0.01, joint damping 0.03 frictionloss 0.001), contact exclusions and actuators, transcribed here.
Menagerie's visual geoms are left out: density 0 and no contacts, so they change nothing in a simulation.

Usage (our venv or any Python with the standard library):
    python research/benchmarks/dexgraspbench/leap_menagerie_fallback.py $DGB_SRC
"""

from __future__ import annotations

import sys
import xml.etree.ElementTree as ET
from pathlib import Path

OURS = Path(__file__).resolve().parents[3] / "manifoundation/core/robots/descriptions/leap_hand/right_hand.xml"
TARGET = "third_party/mujoco_menagerie/leap_hand/right_hand.xml"
MESHES = ("palm_right", "base", "proximal", "medial", "distal", "tip", "thumb_base", "thumb_proximal",
          "thumb_distal", "thumb_tip")  # fmt: skip
# (pos, quat, mass, diaginertia) per body kind, Menagerie's values
FINGER = {
    "bs": ("-0.022516 0.033882 0.016359", "0.388092 0.677951 -0.247713 0.573067", "0.044",
           "1.74972e-05 1.61504e-05 7.21342e-06"),
    "px": ("0.0075 -0.0002 -0.011", "0 0.707107 0 0.707107", "0.032", "4.8853e-06 4.3733e-06 3.0933e-06"),
    "md": ("0.0054215 -0.029148 0.015", "0.687228 0.687228 0.166487 0.166487", "0.037",
           "8.28004e-06 8.1598e-06 5.39516e-06"),
    "ds": ("-0.0008794 -0.027019 0.014594", "0.702905 0.710643 -0.0212937 -0.0214203", "0.016",
           "3.71863e-06 3.02396e-06 1.6518e-06"),
}  # fmt: skip
INERTIAL = {
    "palm": ("-0.049542 -0.042914 -0.010227", "0.565586 0.427629 -0.574956 0.408254", "0.237",
             "0.000407345 0.000304759 0.000180736"),
    "th_mp": FINGER["px"],
    "th_bs": ("0 0 -0.0070806", "0.707107 0.707107 0 0", "0.003", "6.1932e-07 5.351e-07 2.1516e-07"),
    "th_px": ("-0.0020593 0.015912 -0.013733", "0.698518 0.697382 -0.104933 0.121324", "0.038",
              "9.87104e-06 9.32653e-06 4.36203e-06"),
    "th_ds": ("0.00096191 -0.024203 -0.014419", "0.35287 0.311272 -0.632839 0.614904", "0.049",
              "2.08591e-05 2.0402e-05 4.71335e-06"),
    **{f"{f}_{k}": v for f in ("if", "mf", "rf") for k, v in FINGER.items()},
}  # fmt: skip
EXCLUDE = [("palm", f"{f}_{k}") for k in ("bs", "px", "md") for f in ("if", "mf", "rf")]
EXCLUDE += [("palm", "th_mp"), ("palm", "th_bs"), ("palm", "th_px"), ("if_bs", "mf_bs"), ("if_bs", "rf_bs")]
EXCLUDE += [("mf_bs", "rf_bs"), ("th_mp", "if_bs"), ("th_mp", "mf_bs"), ("th_mp", "rf_bs")]


def build(ours: str) -> str:
    """Menagerie's LEAP Hand (right) from our copy of its tree (see module doc)."""
    root = ET.fromstring(ours)
    root.find("compiler").set("meshdir", "./assets/")  # type: ignore[union-attr]
    ET.SubElement(root, "option", integrator="implicitfast", cone="elliptic", impratio="100")
    asset = root.find("asset")
    assert asset is not None
    for m in list(asset):
        asset.remove(m)
    for name in MESHES:
        ET.SubElement(asset, "mesh", name=name.removesuffix("_right"), file=f"{name}.obj")
    default = root.find("default")
    assert default is not None
    # element defaults before the nested classes: a class copies its parent's defaults when it is created
    default.insert(0, ET.Element("geom", solimp="0.999 0.999 0.001 0.0001 1", solref="0.0001 1", friction=".2"))
    default.insert(1, ET.Element("position", kp="3.0", kv="0.01"))
    default.insert(2, ET.Element("joint", damping="0.03", frictionloss="0.001"))
    for cls in default.findall("default"):
        joint = cls.find("joint")
        if joint is not None:
            ET.SubElement(cls, "position", ctrlrange=joint.get("range", ""))
        geom = cls.find("geom")
        if geom is not None:  # tip, thumb_tip
            geom.set("friction", "0.5")
    joints = []
    for body in root.iter("body"):
        pos, quat, mass, diag = INERTIAL[body.get("name", "")]
        body.insert(0, ET.Element("inertial", pos=pos, quat=quat, mass=mass, diaginertia=diag))
        joints += [(j.get("name", ""), j.get("class", "")) for j in body.findall("joint")]
    contact = ET.SubElement(root, "contact")
    for a, b in EXCLUDE:
        ET.SubElement(contact, "exclude", body1=a, body2=b)
    actuator = ET.SubElement(root, "actuator")
    for name, cls in joints:
        ET.SubElement(actuator, "position", name=f"{name}_act", joint=name, **{"class": cls})
    return ET.tostring(root, encoding="unicode")


def main(argv: list[str]) -> int:
    if len(argv) != 1:
        print(__doc__)
        return 2
    target = Path(argv[0]) / TARGET
    if target.exists():
        print(f"{target} exists: nothing to do")
        return 0
    target.parent.mkdir(parents=True, exist_ok=True)
    target.write_text(build(OURS.read_text()))
    print(f"wrote {target}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
