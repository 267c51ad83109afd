"""Hostile robot archives (issue 62): made by the tests of the core and the API and by `mani-lab bench faults`."""

from __future__ import annotations

import io
import zipfile

HAND = (
    '<mujoco model="h"><worldbody><body name="palm"><geom type="box" size=".02 .02 .02"/>'
    '<body name="tip" pos="0 0 .05"><joint name="j" type="hinge" axis="1 0 0" range="0 1"/>'
    '<geom type="sphere" size=".01"/></body></body></worldbody></mujoco>'
)


def include_bomb(depth: int, fan_out: int = 60) -> bytes:
    """``hand.xml`` includes ``l0.xml``; each ``lN.xml`` includes ``l(N+1).xml`` ``fan_out`` times (issue 62)."""
    files = {"hand.xml": HAND.replace("<worldbody>", '<include file="l0.xml"/><worldbody>')}
    for level in range(depth):
        files[f"l{level}.xml"] = "<mujoco>" + f'<include file="l{level + 1}.xml"/>' * fan_out + "</mujoco>"
    files[f"l{depth}.xml"] = '<mujoco><default><geom rgba="1 0 0 1"/></default></mujoco>'
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", zipfile.ZIP_DEFLATED) as z:
        for name, text in files.items():
            z.writestr(name, text)
    return buf.getvalue()
