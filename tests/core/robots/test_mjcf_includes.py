"""MJCF ``<include>`` expansion is bounded while it happens: a bomb of any depth is refused fast and small."""

from __future__ import annotations

import io
import resource
import time
import zipfile

import pytest

from manifoundation.core.robots.description import HandLoadError
from manifoundation.core.robots.user_hand import HandSource, build_user_hand
from research.hostile_archives import include_bomb


@pytest.mark.parametrize("depth", [3, 4, 7])
def test_an_include_bomb_of_any_depth_is_refused_in_well_under_a_second(depth: int) -> None:
    archive = include_bomb(depth)
    assert len(archive) < 2000
    rss_before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    start = time.process_time()
    with pytest.raises(HandLoadError, match="include") as refused:
        build_user_hand(HandSource(name="bomb", archive=archive))
    assert time.process_time() - start < 1.0
    assert (resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - rss_before) / 1024 < 100  # kB → MB
    assert "limit" in str(refused.value)


def test_a_few_includes_still_compile_in_document_order() -> None:
    parts = {
        "hand.xml": '<mujoco model="h"><include file="a.xml"/><worldbody><body name="palm">'
        '<geom type="box" size=".02 .02 .02"/><include file="fingers.xml"/></body></worldbody></mujoco>',
        "a.xml": '<mujoco><default><geom rgba="1 0 0 1"/></default></mujoco>',
        "fingers.xml": '<mujoco><body name="f1" pos="0 0 .05"><joint name="j1" type="hinge" range="0 1"/>'
        '<geom type="sphere" size=".01"/></body><include file="f2.xml"/></mujoco>',
        "f2.xml": '<mujoco><body name="f2" pos="0 .03 .05"><joint name="j2" type="hinge" range="0 1"/>'
        '<geom type="sphere" size=".01"/></body></mujoco>',
    }
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w") as z:
        for name, text in parts.items():
            z.writestr(name, text)
    hand = build_user_hand(HandSource(name="ok", archive=buf.getvalue(), fingertips=["f1", "f2"])).hand
    assert list(hand.joint_names) == ["j1", "j2"]
