"""Examples of a chosen task: a grasp asked for a lift, a push or a turn, with forces that produce it.

Random forces in the friction cones (`research.data.examples`) mostly cancel in translation on a multi-finger
grasp, so their motions are mostly rotations: measured on the round-3 data, the network was flat on a plain lift.
A targeted example picks the task first — a unit scaled wrench near one of the 12 axis directions (a force along
±x, ±y, ±z, or a torque about one; +z, the lift, drawn as often as the other five forces together) — and asks
the grasp for it: a linear programme over 8-sided friction pyramids (`research.data.grasp_sets.pyramid_edges`,
inside the cones) with every normal force ≤ 1 (the refinement's bound) and the smallest normal force as large
as it can be, so every finger presses (the grasp a person would call firm), not only the few a vertex of the
programme would pick. An infeasible programme means this grasp cannot do that task, and another task is drawn.
Measured on the dense data's Allegro and LEAP grasps (μ = 0.65, 259 grasps of four objects): a force along one
axis is feasible for 0-26 % of the grasps, a pure torque for almost none (the ≤ 1 bound against the levers a
fingertip grasp has), so the tasks that make it into the data are mostly lifts and pushes.

The labels are made as for a random-force example (`research.data.examples.rigid_labels`), so a targeted example
is an ordinary rigid example to the data set and the grasp sets.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from scipy.optimize import linprog

from research.data.examples import FRICTION, ObjectInfo, is_unseen_motion, rigid_labels
from research.data.grasp_sets import pyramid_forces, pyramid_programme

FORCE_SHARE = 0.7  # of targeted examples, a force (translation); the rest a torque (turn in place)
LIFT_SHARE = 0.5  # of the forces, +z (the lift); the other five force directions share the rest
JITTER = 0.25  # size of the random part added to the axis direction, before normalising
TARGET_TRIES = 24  # tasks drawn per example; one linear programme (≈ 1 ms) each

# the 12 axis directions of the scaled wrench: +x, −x, +y, −y, +z, −z forces, then the same torques
AXIS_DIRECTIONS = np.kron(np.eye(6), [[1.0], [-1.0]])
_OTHER_FORCE = (1.0 - LIFT_SHARE) / 5.0
AXIS_WEIGHTS = np.concatenate([
    FORCE_SHARE * np.array([_OTHER_FORCE] * 4 + [LIFT_SHARE, _OTHER_FORCE]), np.full(6, (1.0 - FORCE_SHARE) / 6.0),
])  # fmt: skip


def sample_target(rng: np.random.Generator) -> np.ndarray:
    """A unit scaled wrench (6,) near an axis direction: a lift (+z force) most often, else a push or a turn."""
    w = AXIS_DIRECTIONS[rng.choice(len(AXIS_DIRECTIONS), p=AXIS_WEIGHTS)] + JITTER * rng.normal(size=6) / np.sqrt(6.0)
    unit: np.ndarray = w / np.linalg.norm(w)
    return unit


def firm_forces(
    contacts: np.ndarray, normals: np.ndarray, mu: float, target: np.ndarray, centre: np.ndarray, length: float
) -> np.ndarray | None:
    """Forces (m, 3) giving the scaled wrench ``target`` with the smallest normal force largest, or None.

    Args:
        contacts, normals: (m, 3) contact points and outward normals.
        mu: friction coefficient.
        target: (6,) the unit scaled wrench to produce.
        centre, length: the object's centre of mass and characteristic length.
    """
    m = len(contacts)
    edges, wrench, normal = pyramid_programme(contacts, normals, mu, centre, length)
    t_column = np.zeros((m, 1))  # one more variable, t, the smallest normal force: normal ≤ 1 and ≥ t
    a_ub = np.vstack([np.hstack([normal, t_column]), np.hstack([-normal, t_column + 1.0])])
    b_ub = np.concatenate([np.ones(m), np.zeros(m)])
    cost = np.zeros(wrench.shape[1] + 1)
    cost[-1] = -1.0  # maximise t
    a_eq = np.hstack([wrench, np.zeros((6, 1))])
    res = linprog(cost, A_ub=a_ub, b_ub=b_ub, A_eq=a_eq, b_eq=target, bounds=(0, None), method="highs")
    if res.status != 0:
        return None
    return pyramid_forces(res.x[:-1], edges)


def make_targeted_example(
    info: ObjectInfo, contacts: np.ndarray, normals: np.ndarray, rng: np.random.Generator, *, want_unseen: bool
) -> dict[str, Any] | None:
    """One rigid example of a sampled task (lift, push, turn) for a grasp's contacts, or None.

    None when no task of the wanted split that the grasp can produce was drawn in :data:`TARGET_TRIES` tries.
    """
    mu = float(rng.uniform(*FRICTION))
    for _ in range(TARGET_TRIES):
        target = sample_target(rng)
        if is_unseen_motion(target) != want_unseen:
            continue
        forces = firm_forces(contacts, normals, mu, target, info.centre, info.length)
        if forces is not None:
            return rigid_labels(info, contacts, normals, forces, mu, rng)
    return None


__all__ = ["firm_forces", "make_targeted_example", "sample_target"]
