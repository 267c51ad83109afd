"""A user URDF is untrusted: hardened parsing, caps, no file access, structural validation."""

from __future__ import annotations

from unittest import mock

import numpy as np
import pytest
import torch

from manifoundation.core.robots import HandLoadError, UnknownHand, get_hand, list_hands, load_hand
from manifoundation.core.robots.urdf import MAX_LINKS

FINGER = """<?xml version="1.0" encoding="utf-8"?>
<robot name="pinch">
  <link name="palm"><collision><geometry><box size="0.08 0.08 0.02"/></geometry></collision></link>
  <link name="finger">
    <collision><origin xyz="0 0 0.03"/><geometry>{geom}</geometry></collision>
  </link>
  <joint name="j1" type="{jtype}">
    <parent link="{parent}"/><child link="finger"/>
    <origin xyz="0 0 0.01"/><axis xyz="1 0 0"/><limit lower="{lower}" upper="1.0" effort="1" velocity="1"/>
  </joint>
  {extra}
</robot>
"""


def _urdf(**kw: str) -> bytes:
    args = {"geom": '<box size="0.02 0.02 0.06"/>', "jtype": "revolute", "parent": "palm", "lower": "-1.0", "extra": ""}
    args.update(kw)
    return FINGER.format(**args).encode()


def test_valid_user_urdf_loads_with_primitives() -> None:
    hand = load_hand(_urdf(), fingertips=["finger"], tip_offsets=[[0, 0, 0.06]], name="pinch")
    assert hand.dof == 1 and hand.joint_names == ["j1"] and hand.name == "pinch"
    assert set(hand.collision_meshes) == {"palm", "finger"}
    tips = hand.fingertips(torch.zeros(1, 3), torch.tensor([[1.0, 0, 0, 0]]), torch.zeros(1, 1))
    np.testing.assert_allclose(tips[0, 0].numpy(), [0, 0, 0.07], atol=1e-6)


def test_billion_laughs_is_rejected() -> None:
    bomb = b"""<?xml version="1.0"?>
<!DOCTYPE lolz [<!ENTITY lol "lol"><!ENTITY lol2 "&lol;&lol;&lol;&lol;&lol;&lol;&lol;&lol;&lol;&lol;">
<!ENTITY lol3 "&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;&lol2;">]>
<robot name="&lol3;"><link name="palm"/></robot>"""
    with pytest.raises(HandLoadError, match="unsafe XML"):
        load_hand(bomb, fingertips=["palm"])


def test_external_entity_is_rejected() -> None:
    xxe = b"""<?xml version="1.0"?><!DOCTYPE r [<!ENTITY x SYSTEM "file:///etc/passwd">]>
<robot name="r"><link name="&x;"/></robot>"""
    with pytest.raises(HandLoadError, match="unsafe XML"):
        load_hand(xxe, fingertips=["palm"])


def test_mesh_filename_is_never_opened() -> None:
    doc = _urdf(geom='<mesh filename="/etc/passwd"/>')
    with (
        mock.patch("builtins.open", side_effect=AssertionError("opened a file")),
        mock.patch("trimesh.load", side_effect=AssertionError("loaded a mesh")),
    ):
        hand = load_hand(doc, fingertips=["finger"])
    assert "finger" not in hand.collision_meshes  # the mesh was ignored, the palm box kept
    assert "palm" in hand.collision_meshes


def test_size_cap() -> None:
    with pytest.raises(HandLoadError, match="limit"):
        load_hand(_urdf(extra="<!--" + "x" * 2_100_000 + "-->"), fingertips=["finger"])


def test_link_count_cap() -> None:
    links = "".join(f'<link name="l{i}"/>' for i in range(MAX_LINKS + 1))
    with pytest.raises(HandLoadError, match="limit"):
        load_hand(_urdf(extra=links), fingertips=["finger"])


def test_cycle_is_rejected() -> None:
    extra = """<link name="a"/><joint name="j2" type="fixed"><parent link="finger"/><child link="a"/></joint>
    <joint name="j3" type="fixed"><parent link="a"/><child link="palm"/></joint>"""
    with pytest.raises(HandLoadError, match="cycle"):
        load_hand(_urdf(extra=extra), fingertips=["finger"])


def test_missing_parent_is_rejected() -> None:
    with pytest.raises(HandLoadError, match="parent link 'ghost' does not exist"):
        load_hand(_urdf(parent="ghost"), fingertips=["finger"])


def test_unknown_fingertip_is_rejected() -> None:
    with pytest.raises(HandLoadError, match="unknown fingertip"):
        load_hand(_urdf(), fingertips=["nope"])


@pytest.mark.parametrize("lower", ["nan", "-inf", "1e999"])
def test_non_finite_limits_are_rejected(lower: str) -> None:
    with pytest.raises(HandLoadError, match="non-finite"):
        load_hand(_urdf(lower=lower), fingertips=["finger"])


@pytest.mark.parametrize(
    "doc, match",
    [
        (b"<robot><link", "malformed XML"),
        (b"<mujoco/>", "expected <robot>"),
        (_urdf(jtype="floating"), "unsupported type"),
        (_urdf(lower="2.0"), "lower limit"),
    ],
)
def test_malformed_documents(doc: bytes, match: str) -> None:
    with pytest.raises(HandLoadError, match=match):
        load_hand(doc, fingertips=["finger"])


def test_bad_tip_offsets() -> None:
    with pytest.raises(HandLoadError, match="tip_offsets"):
        load_hand(_urdf(), fingertips=["finger"], tip_offsets=[[0, 0, float("nan")]])


def test_unknown_builtin_lists_names() -> None:
    with pytest.raises(UnknownHand) as err:
        get_hand("robotiq")
    assert all(n in str(err.value) for n in list_hands())
    assert isinstance(err.value, LookupError)
    builtins = {"allegro", "leap_hand", "leap_kaizen", "shadow", "panda_gripper", "barrett", "kinova3f"}
    assert set(list_hands()) == builtins and set(list_hands(aliases=True)) == builtins | {"leap"}


def test_unknown_mimic_source_and_palm() -> None:
    extra = """<link name="g"><collision><geometry><sphere radius="0.01"/></geometry></collision></link>
    <joint name="j2" type="revolute"><parent link="palm"/><child link="g"/><limit lower="0" upper="1"/>
    <mimic joint="nope"/></joint>"""
    with pytest.raises(HandLoadError, match="mimics unknown"):
        load_hand(_urdf(extra=extra), fingertips=["finger"])
    with pytest.raises(HandLoadError, match="root link"):
        load_hand(_urdf(), fingertips=["finger"], palm="nope")


def test_rigid_hand_without_joints_and_continuous_joint() -> None:
    doc = b"""<robot name="r"><link name="palm"><collision><geometry><box size="0.1 0.1 0.1"/></geometry>
    </collision></link><link name="tip"/><joint name="f" type="fixed"><parent link="palm"/><child link="tip"/>
    <origin xyz="0 0 0.1"/></joint></robot>"""
    hand = load_hand(doc, fingertips=["tip"])
    assert hand.dof == 0
    p, J = hand.fingertip_jacobians(torch.zeros(2, 3), torch.tensor([[1.0, 0, 0, 0]] * 2), torch.zeros(2, 0))
    assert J.shape == (2, 1, 3, 6)
    np.testing.assert_allclose(p[0, 0].numpy(), [0, 0, 0.1])
    hand = load_hand(_urdf(jtype="continuous"), fingertips=["finger"])
    assert hand.lower[0] == pytest.approx(-np.pi) and hand.upper[0] == pytest.approx(np.pi)


def test_geometry_count_and_extent_caps() -> None:
    many = '<link name="m">' + '<collision><geometry><sphere radius="0.01"/></geometry></collision>' * 600 + "</link>"
    with pytest.raises(HandLoadError, match="geometry elements"):
        load_hand(_urdf(extra=many), fingertips=["finger"])
    with pytest.raises(HandLoadError, match="sizes"):
        load_hand(_urdf(geom='<box size="100 0.02 0.02"/>'), fingertips=["finger"])


def test_bad_rest_axis_and_no_geometry() -> None:
    with pytest.raises(HandLoadError, match="rest"):
        load_hand(_urdf(), fingertips=["finger"], rest=[0.1, 0.2])
    with pytest.raises(HandLoadError, match="rest"):
        load_hand(_urdf(), fingertips=["finger"], rest=[float("nan")])
    with pytest.raises(HandLoadError, match="approach_axis"):
        load_hand(_urdf(), fingertips=["finger"], approach_axis=[0, 0, 0])
    only_meshes = b"""<robot name="r"><link name="palm"><collision><geometry><mesh filename="x.stl"/></geometry>
    </collision></link></robot>"""
    with pytest.raises(HandLoadError, match="no collision geometry"):
        load_hand(only_meshes, fingertips=["palm"])
