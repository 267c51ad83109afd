"""The squeeze's imbalance on the Panda gripper, whose pads move along ±y with one joint: known answers."""

from __future__ import annotations

import numpy as np
import pytest

from manifoundation.core.refine.squeeze import squeeze_imbalance
from manifoundation.core.refine.state import HandPose
from manifoundation.core.robots import get_hand

HALF, Z, RHO = 0.02, 0.1, 0.05
POSE = HandPose(np.zeros(3), np.array([1.0, 0.0, 0.0, 0.0]), np.array([HALF]))
CENTRE = np.array([0.0, 0.0, Z])


def test_opposed_pads_on_one_line_are_balanced() -> None:
    points = np.array([[0.0, HALF, Z], [0.0, -HALF, Z]])
    normals = np.array([[0.0, 1.0, 0.0], [0.0, -1.0, 0.0]])
    assert squeeze_imbalance(get_hand("panda_gripper"), POSE, points, normals, CENTRE, RHO) == pytest.approx(0.0)


def test_opposed_pads_off_one_line_turn_the_object() -> None:
    # equal pushes ±y at heights differing by 2 cm: net torque 0.5·(z2 − z1) about x, over ρ
    points = np.array([[0.0, HALF, Z + 0.01], [0.0, -HALF, Z - 0.01]])
    normals = np.array([[0.0, 1.0, 0.0], [0.0, -1.0, 0.0]])
    got = squeeze_imbalance(get_hand("panda_gripper"), POSE, points, normals, CENTRE, RHO)
    assert got == pytest.approx(0.5 * 0.02 / RHO)


def test_pushes_the_same_way_are_all_imbalance() -> None:
    points = np.array([[0.0, HALF, Z], [0.0, -HALF, Z]])
    normals = np.array([[0.0, 1.0, 0.0], [0.0, 1.0, 0.0]])
    assert squeeze_imbalance(get_hand("panda_gripper"), POSE, points, normals, CENTRE, RHO) == pytest.approx(1.0)
