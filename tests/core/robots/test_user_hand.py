"""User hands from third-party packages: cut at the palm, meshes kept, kinematics checked against an independent
implementation (the audit's pytorch-kinematics / MuJoCo forward kinematics), couplings, hostile MJCF."""

from __future__ import annotations

import io
import zipfile

import numpy as np
import pytest
import torch

from manifoundation.core.robots.description import HandLoadError
from manifoundation.core.robots.hand import Hand
from manifoundation.core.robots.thirdparty import third_party_hands
from manifoundation.core.robots.user_hand import HandSource, build_user_hand
from research.audit.kinematics import MjcfKinematics, UrdfKinematics

HANDS = third_party_hands()


def needs(name: str) -> None:
    if not HANDS[name].available:
        pytest.fail(f"{HANDS[name].package} is a test dependency: pip install {HANDS[name].package}")


def our_poses(hand: Hand, q: np.ndarray) -> dict[str, np.ndarray]:
    d = torch.float64
    poses = hand.link_poses(
        torch.zeros(1, 3, dtype=d), torch.tensor([[1.0, 0, 0, 0]], dtype=d), torch.as_tensor(q[None])
    )
    return {k: v[0].numpy() for k, v in poses.items()}


def random_q(hand: Hand, seed: int) -> np.ndarray:
    return np.random.default_rng(seed).uniform(hand.lower, hand.upper)


def test_the_g1_dex3_hand_is_cut_from_the_humanoid_at_its_palm() -> None:
    needs("g1_dex3")
    g1 = HANDS["g1_dex3"]
    built = build_user_hand(HandSource(name="g1", archive=g1.archive(), palm=g1.palm))
    hand = built.hand
    assert hand.dof == 7 and all(j.startswith("right_hand_") for j in hand.joint_names)
    assert sorted(built.fingertips) == [
        "right_hand_index_1_link",
        "right_hand_middle_1_link",
        "right_hand_thumb_2_link",
    ]
    assert "45 links and 36 joints outside the palm's sub-tree dropped" in built.ignored[0]
    assert len(hand.collision_meshes["right_hand_palm_link"].faces) > 10_000  # the STL, not a primitive
    assert len(hand.sphere_radii) > 20 and len(hand.surface_points) == 1024
    assert all(a > 1e-4 for a in built.pad_areas)
    # forward kinematics agree with pytorch-kinematics on the package's own file (the audit's)
    ref = UrdfKinematics(g1.description, g1.palm)
    for seed in range(3):
        q = random_q(hand, seed)
        theirs = ref.palm_transforms(dict(zip(hand.joint_names, q, strict=True)))
        ours = our_poses(hand, q)
        for link in built.fingertips:
            assert np.allclose(ours[link], theirs[link], atol=1e-9), link


def test_an_mjcf_hand_keeps_mujoco_frames_and_joint_references() -> None:
    needs("orca")
    orca = HANDS["orca"]
    built = build_user_hand(HandSource(name="orca", archive=orca.archive(), palm=orca.palm))
    hand = built.hand
    assert hand.dof == 16 and len(built.fingertips) == 5 and built.format == "mjcf"
    assert any("texture" in note for note in built.ignored)
    ref = MjcfKinematics(orca.description, orca.palm)  # MuJoCo's own forward kinematics of the package file
    for seed in range(3):
        q = random_q(hand, seed)
        theirs = ref.palm_transforms(dict(zip(hand.joint_names, q, strict=True)))
        ours = our_poses(hand, q)
        for body in built.fingertips:
            assert np.allclose(ours[body], theirs[body], atol=1e-9), body
    # the default rest pose is the one the file draws (its joint refs), inside the limits
    assert np.all(hand.rest >= hand.lower) and np.all(hand.rest <= hand.upper)
    assert hand.rest[hand.joint_names.index("right_thumb_abd")] == pytest.approx(-0.73304)


COUPLED = """<mujoco><compiler angle="radian"/><worldbody><body name="palm"><geom type="box" size=".02 .02 .005"/>
  <body name="a" pos="0 0 .02"><joint name="ja" axis="1 0 0" range="0 1"/><geom type="box" size=".005 .005 .01"/>
    <body name="b" pos="0 0 .02"><joint name="jb" axis="1 0 0" range="0 2"/><geom type="box" size=".005 .005 .01"/>
    </body></body>
  <body name="c" pos="0 .03 .02"><joint name="jc" axis="1 0 0" range="0 1"/><geom type="box" size=".005 .005 .01"/>
  </body></body></worldbody>
  <equality><joint joint1="jb" joint2="ja" polycoef="0.1 1.5 0 0 0"/><connect body1="b" body2="c" anchor="0 0 0"/>
  </equality></mujoco>"""


def test_mjcf_equality_couplings_are_honoured_or_reported() -> None:
    built = build_user_hand(HandSource(name="c", mjcf=COUPLED))
    assert built.hand.joint_names == ["ja", "jc"]  # jb follows ja
    assert any("jb = 1.5 * ja + 0.1 (honoured)" in c for c in built.couplings)
    assert any("connect" in c and "free" in c for c in built.couplings)
    q = np.array([0.4, 0.0])
    tip = our_poses(built.hand, q)["b"]
    angle = 0.4 + (0.1 + 1.5 * 0.4)  # both hinges about x
    assert np.allclose(tip[:3, :3][1:, 1:], [[np.cos(angle), -np.sin(angle)], [np.sin(angle), np.cos(angle)]])


def _zip(files: dict[str, str | bytes]) -> bytes:
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w") as z:
        for name, data in files.items():
            z.writestr(name, data)
    return buf.getvalue()


@pytest.mark.parametrize(
    ("extra", "words"),
    [
        ('<include file="../../etc/hosts"/>', "leaves the archive"),
        ('<include file="/etc/hosts"/>', "absolute"),
        ('<asset><mesh name="m" file="/etc/passwd"/></asset>', "absolute"),
        ('<asset><mesh name="m" file="nothere.stl"/></asset>', "not in the archive"),
        ('<extension><plugin plugin="mujoco.elasticity.solid"/></extension>', "<extension>"),
        ('<asset><hfield name="h" file="/etc/passwd"/></asset>', None),  # dropped, never read: compiles
    ],
)
def test_hostile_mjcf_never_reads_outside_the_archive(extra: str, words: str | None) -> None:
    doc = COUPLED.replace("<worldbody>", extra + "<worldbody>", 1)
    if words is None:
        assert build_user_hand(HandSource(name="h", archive=_zip({"hand.xml": doc}))).hand.dof == 2
        return
    with pytest.raises(HandLoadError, match=words.replace("<", "<?")):
        build_user_hand(HandSource(name="h", archive=_zip({"hand.xml": doc})))


def test_fingertips_and_palm_are_checked() -> None:
    with pytest.raises(HandLoadError, match="palm: 'nope' is not a link"):
        build_user_hand(HandSource(name="c", mjcf=COUPLED, palm="nope"))
    with pytest.raises(HandLoadError, match="fingertips"):
        build_user_hand(HandSource(name="c", mjcf=COUPLED, fingertips=["ghost"]))
    # the caller's fingertips override the leaves
    assert build_user_hand(HandSource(name="c", mjcf=COUPLED, fingertips=["a"])).fingertips == ["a"]


def test_a_urdf_link_drawn_only_through_primitives_takes_its_visual_mesh() -> None:
    """A finger that collides through a box drawn around it but ships its real shape as a visual mesh is built from
    the mesh (the surface the robot touches with, as the physics test judges it); a link whose collision is a mesh
    keeps that mesh."""
    import trimesh

    finger = trimesh.creation.cylinder(radius=0.008, height=0.04, sections=24)
    finger.apply_translation([0, 0, 0.02])
    stl = trimesh.exchange.stl.export_stl(finger)
    palm = trimesh.creation.box(extents=[0.06, 0.06, 0.02])
    palm_stl = trimesh.exchange.stl.export_stl(palm)
    urdf = """<robot name="r">
      <link name="palm"><collision><geometry><mesh filename="palm.stl"/></geometry></collision>
        <visual><geometry><box size="0.2 0.2 0.2"/></geometry></visual></link>
      <link name="tip"><collision><origin xyz="0 0 0.02"/><geometry><box size="0.03 0.03 0.05"/></geometry></collision>
        <visual><geometry><mesh filename="tip.stl"/></geometry></visual></link>
      <joint name="j" type="revolute"><parent link="palm"/><child link="tip"/><origin xyz="0 0 0.01"/>
        <axis xyz="1 0 0"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
    </robot>"""
    built = build_user_hand(HandSource(name="u", archive=_zip({"hand.urdf": urdf, "tip.stl": stl,
                                                                "palm.stl": palm_stl})))  # fmt: skip
    tip, base = built.hand.collision_meshes["tip"], built.hand.collision_meshes["palm"]
    assert len(tip.vertices) == len(finger.vertices) and np.allclose(tip.extents, finger.extents)  # not the box
    assert np.allclose(base.extents, palm.extents)  # its collision mesh, not the 20 cm visual box
