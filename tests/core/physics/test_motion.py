"""The executed target-motion test (manifoundation.core.physics.simulate_motion) on cases whose answer is known."""

from __future__ import annotations

import numpy as np
import trimesh

from manifoundation.core.physics import PhysicsResult, Protocol, from_mesh, simulate_motion
from manifoundation.core.robots import get_hand

DOWN = np.array([0.0, 1.0, 0.0, 0.0])  # the palm turned 180° about x: the Panda's fingers point down (−z)
PAD_Z = -0.1  # the pads' height below the palm in the world frame
HALF = 0.02  # the box is 3 x 4 x 3 cm: its ±y faces 2 cm from its centre
LIFT = np.array([0.0, 0.0, 0.05])


def _carry(q: float, rotation: np.ndarray | None = None) -> PhysicsResult:
    hand = get_hand("panda_gripper")
    box = trimesh.creation.box(extents=[0.03, 2 * HALF, 0.03])
    box.apply_translation([0.0, 0.0, PAD_Z])
    contacts = np.array([[0.0, -HALF, PAD_Z], [0.0, HALF, PAD_Z]])  # turned palm: the left pad is at −y
    normals = np.array([[0.0, -1.0, 0.0], [0.0, 1.0, 0.0]])
    return simulate_motion(hand, np.zeros(3), DOWN, np.array([q]), contacts, normals, hand.fingertip_links,
                           from_mesh(box.vertices, box.faces), LIFT, rotation)  # fmt: skip


def test_tolerance_is_stated() -> None:
    p = Protocol()
    assert (p.target_translation, p.target_rotation) == (0.01, 10.0)
    assert (p.motion_seconds, p.motion_hold_seconds, p.gravity, p.mass) == (1.0, 0.5, 9.81, 0.1)


def test_gripper_squeezing_a_box_lifts_it_five_cm() -> None:
    r = _carry(HALF)
    assert r.test == "motion" and r.trials == [] and r.motion is not None
    assert r.success and r.reason == "reached", r.motion
    assert r.motion.translation_error < 0.002 and r.motion.rotation_error < 1.0 and not r.motion.dropped
    assert r.contacts_after_squeeze == 2


def test_gripper_squeezing_a_box_lifts_and_turns_it() -> None:
    turn = np.array([np.cos(np.radians(15)), 0.0, 0.0, np.sin(np.radians(15))])  # 30° about z, about the centre
    r = _carry(HALF, turn)
    assert r.success and r.motion is not None and r.motion.rotation_error < 2.0, r.motion


def test_open_gripper_leaves_the_box_behind() -> None:
    r = _carry(HALF + 0.02)
    assert not r.success and r.reason == "dropped" and r.motion is not None
    assert r.motion.dropped and r.motion.translation_error > 0.05  # it fell under gravity
    assert r.contacts_after_squeeze == 0
