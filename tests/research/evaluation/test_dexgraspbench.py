"""The conversion of our answers to DexGraspBench's format, checked without a DGB copy.

`dexgraspbench_fk.json` holds DGB's own forward kinematics (its hand XMLs at commit 1e7a5a6, MuJoCo 3.3.2, written
by ``research/benchmarks/dexgraspbench/dgb_driver.py --fk``) for two random joint vectors per hand.
"""

from __future__ import annotations

import json
from pathlib import Path

import mujoco
import numpy as np
import pytest
import trimesh

from manifoundation.core.physics import from_mesh
from manifoundation.core.physics.visual import physics_description
from manifoundation.core.robots import get_hand
from manifoundation.core.robots.registry import DESCRIPTIONS
from research.evaluation.dexgraspbench import (
    HANDS,
    RESET_GUARD,
    _matrix,
    convert_answer,
    dgb_hand,
    dgb_joint_values,
    moving_joint_values,
    root_pose,
    write_object,
)
from research.evaluation.dexgraspbench_fk import dgb_bodies, max_distance, our_bodies

FIXTURE = json.loads((Path(__file__).parent / "dexgraspbench_fk.json").read_text())
DGB_JOINTS = {"leap_hand": 16, "allegro": 16, "shadow": 22}  # hinge joints of DGB's hand XMLs
FK_TOLERANCE_MM = {"leap_hand": 1e-6, "allegro": 1e-3, "shadow": 3.0}  # Shadow: two different models (see module)


def _random_pose(rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    q = rng.normal(size=4)
    return rng.normal(scale=0.1, size=3), q / np.linalg.norm(q)


@pytest.mark.parametrize("name", sorted(HANDS))
def test_every_moving_joint_maps_to_a_distinct_dgb_joint(name: str) -> None:
    hand = get_hand(name)
    moving = [j.name for j in physics_description(hand).joints if j.type != "fixed"]
    mapping = dgb_hand(name)
    assert set(moving) == set(mapping.joints)
    targets = [t for t, _ in mapping.joints.values()]
    assert len(set(targets)) == len(targets) == DGB_JOINTS[name]
    assert set(mapping.bodies) <= set(physics_description(hand).links)


def test_hands_without_a_dgb_counterpart_are_refused() -> None:
    with pytest.raises(KeyError, match="no DexGraspBench counterpart"):
        dgb_hand("leap")  # LEAP KAIZEN, not the LEAP Hand


def test_root_pose_composed_with_the_palm_body_pose_gives_the_palm_pose() -> None:
    rng = np.random.default_rng(0)
    for mapping in HANDS.values():
        pos, quat = _random_pose(rng)
        root = root_pose(mapping, pos, quat)
        R_root, (p_rp, q_rp) = _matrix(root[3:]), mapping.palm_in_root
        assert np.allclose(R_root @ np.array(p_rp) + root[:3], pos, atol=1e-12)
        assert np.allclose(R_root @ _matrix(np.array(q_rp)), _matrix(quat), atol=1e-12)


@pytest.mark.parametrize("case", range(len(FIXTURE["cases"])))
def test_converted_answer_puts_dgb_bodies_where_ours_are(case: int) -> None:
    """Our FK (the physics test's model) at a random palm pose vs DGB's FK (the fixture) at the converted pose."""
    c = FIXTURE["cases"][case]
    hand = get_hand(c["hand"])
    pos, quat = _random_pose(np.random.default_rng(case))
    ours = our_bodies(hand, pos, quat, np.array(c["q"]))
    theirs = dgb_bodies(c["hand"], root_pose(dgb_hand(c["hand"]), pos, quat), c["bodies"])
    assert 1000 * max_distance(ours, theirs) < FK_TOLERANCE_MM[c["hand"]]


def test_leap_hand_conversion_on_our_own_mjcf() -> None:
    """Our LEAP Hand MJCF is Menagerie's body tree (palm at (0, 0, 0.1), turned): the converted root pose and joint
    values, applied to it, put every body where our physics model has it."""
    hand = get_hand("leap_hand")
    model = mujoco.MjModel.from_xml_path(str(DESCRIPTIONS / "leap_hand" / "right_hand.xml"))
    data = mujoco.MjData(model)
    rng = np.random.default_rng(1)
    q = np.asarray(hand.lower) + (np.asarray(hand.upper) - np.asarray(hand.lower)) * rng.random(len(hand.lower))
    for name, value in dgb_joint_values(dgb_hand("leap_hand"), moving_joint_values(hand, q)).items():
        data.qpos[model.jnt_qposadr[model.joint(name).id]] = value
    mujoco.mj_kinematics(model, data)
    xml_world = {model.body(i).name: data.xpos[i].tolist() for i in range(model.nbody)}
    pos, quat = _random_pose(rng)
    theirs = dgb_bodies("leap_hand", root_pose(dgb_hand("leap_hand"), pos, quat), xml_world)
    assert max_distance(our_bodies(hand, pos, quat, q), theirs) < 1e-12


def test_shadow_tied_joints_get_their_tied_values() -> None:
    hand = get_hand("shadow")
    q = np.asarray(hand.rest, float)
    values = dgb_joint_values(dgb_hand("shadow"), moving_joint_values(hand, q))
    ff_j1 = q[list(hand.joint_names).index("robot0:FFJ1")]
    assert values["rh_FFJ1"] == pytest.approx(0.00805 / 0.00705 * ff_j1)  # our J0 = DGB's J1 (distal)


def test_object_folder_gives_dgb_its_mass_and_the_answer_moves_with_the_object(tmp_path: Path) -> None:
    box = trimesh.creation.box(extents=(0.04, 0.06, 0.08))
    shape = from_mesh(box.vertices + 0.3, box.faces)
    centre = write_object(shape, tmp_path / "box")
    info = json.loads((tmp_path / "box" / "info" / "simplified.json").read_text())
    volume = info["mass"] / (info["density"] * info["scale"] ** 3)  # DGB's obj_coef at obj_scale 1
    assert volume == pytest.approx(0.04 * 0.06 * 0.08)  # DGB's density 0.1 kg / volume: 0.1 kg in all
    assert len(list((tmp_path / "box" / "urdf" / "meshes").glob("convex_piece_*.obj"))) == len(shape.pieces)
    assert np.allclose(centre, 0.3)
    hand = get_hand("allegro")
    record = {"hand": "allegro", "joints": list(hand.joint_names), "palm_position": [0.3, 0.3, 0.45],
              "palm_quaternion": [1.0, 0.0, 0.0, 0.0], "grasp": list(hand.rest), "pregrasp": list(hand.rest),
              "squeeze": list(hand.rest)}  # fmt: skip
    job = convert_answer(hand, record, centre, tmp_path / "box")
    assert job["obj_pose"][:3] == RESET_GUARD.tolist()
    assert np.allclose(job["root"][:3], RESET_GUARD + np.array([0.0, 0.0, 0.15]))  # the palm 15 cm above the centre
    assert set(job["grasp"]) == {t for t, _ in dgb_hand("allegro").joints.values()}
