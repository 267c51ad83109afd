"""The audit's closure test with soft-finger contacts (a parallel gripper's pads)."""

import numpy as np

from research.audit.wrench import closure_epsilon


def test_two_opposed_pads_are_in_closure_only_as_soft_fingers():
    """Two antipodal contacts across a 4 cm box: point contacts cannot resist a moment about the line between
    them (never closure); soft fingers with a 5 mm torsional radius can."""
    points = np.array([[0.02, 0.0, 0.0], [-0.02, 0.0, 0.0]])
    normals = np.array([[1.0, 0.0, 0.0], [-1.0, 0.0, 0.0]])
    centre, length = np.zeros(3), 0.03
    assert closure_epsilon(points, normals, 0.8, centre, length) == 0.0
    assert closure_epsilon(points, normals, 0.8, centre, length, torsion=0.005) > 0.0


def test_soft_fingers_do_not_make_a_one_sided_grasp_closed():
    """Two contacts on the same face push the same way: no torsion makes that a closure."""
    points = np.array([[0.02, 0.01, 0.0], [0.02, -0.01, 0.0]])
    normals = np.array([[1.0, 0.0, 0.0], [1.0, 0.0, 0.0]])
    assert closure_epsilon(points, normals, 0.8, np.zeros(3), 0.03, torsion=0.005) == 0.0
