"""Targeted examples: the firm forces produce the asked wrench inside the true friction cones; the task mix has
the lifts it promises; a grasp that cannot do a task gives none; generation writes them as rigid examples."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np

from research.data.generate import run_shard
from research.data.targeted import AXIS_DIRECTIONS, FORCE_SHARE, LIFT_SHARE, firm_forces, sample_target

from .test_generate import CFG

CENTRE = np.zeros(3)
LENGTH = 0.05


def _wrench(contacts: np.ndarray, forces: np.ndarray) -> np.ndarray:
    """Scaled wrench [Σ f; Σ c × f / ρ], written out here rather than through the refinement's grasp maps."""
    return np.concatenate([forces.sum(0), np.cross(contacts - CENTRE, forces).sum(0) / LENGTH])


def test_firm_forces_lift_a_sphere_held_by_four_with_every_finger_pressing() -> None:
    contacts = np.array([[0.05, 0, 0], [-0.05, 0, 0], [0, 0.05, 0], [0, -0.05, 0]])
    normals = contacts / 0.05
    mu = 0.5
    lift = np.array([0.0, 0, 1, 0, 0, 0])
    forces = firm_forces(contacts, normals, mu, lift, CENTRE, LENGTH)
    assert forces is not None
    np.testing.assert_allclose(_wrench(contacts, forces), lift, atol=1e-7)
    normal = np.einsum("ij,ij->i", forces, -normals)
    tangential = np.linalg.norm(forces + normal[:, None] * normals, axis=1)
    assert np.all(tangential <= mu * normal + 1e-9)  # the round cone, not the pyramid
    assert np.all(normal <= 1.0 + 1e-9) and normal.min() > 0.1  # each finger presses, none past the bound


def test_a_grasp_that_cannot_do_the_task_gives_no_forces() -> None:
    below = np.array([[0.0, 0, -0.05]])  # one finger under the object: it can lift, it cannot pull down
    normals = np.array([[0.0, 0, -1]])
    assert firm_forces(below, normals, 0.5, np.array([0.0, 0, 1, 0, 0, 0]), CENTRE, LENGTH) is not None
    assert firm_forces(below, normals, 0.5, np.array([0.0, 0, -1, 0, 0, 0]), CENTRE, LENGTH) is None


def test_sampled_tasks_are_unit_and_lifts_come_as_often_as_promised() -> None:
    rng = np.random.default_rng(0)
    targets = np.array([sample_target(rng) for _ in range(4000)])
    np.testing.assert_allclose(np.linalg.norm(targets, axis=1), 1.0, atol=1e-12)
    nearest = np.argmax(targets @ AXIS_DIRECTIONS.T, axis=1)
    assert abs(np.mean(nearest == 4) - FORCE_SHARE * LIFT_SHARE) < 0.03  # row 4: +z, the lift
    assert abs(np.mean(nearest < 6) - FORCE_SHARE) < 0.03
    assert len(set(nearest.tolist())) == 12


def test_generation_writes_targeted_examples_as_rigid_examples(tmp_path: Path) -> None:
    cfg = replace(CFG, objects_per_shard=2, hands=("allegro",), test_fraction=0.0, unseen_motion_fraction=0.0,
                  examples_per_grasp=0, targeted_per_grasp=3, articulated_fraction=1.0)  # fmt: skip
    result = run_shard(cfg, 0, str(tmp_path))
    assert result.examples > 0
    with np.load(tmp_path / result.file) as z:
        assert not z["articulated"].any()  # a chosen task is a rigid one, whatever the articulated share
        assert np.all(z["heat"].max(axis=1) > 0.5)  # a contact region on the cloud
        length = z["object_length"][z["obj_index"]]
        turned = np.linalg.norm(z["delta_theta"], axis=1) * length
        assert np.median(np.linalg.norm(z["delta_x"], axis=1) / turned) > 1.0  # forces drawn: mostly translations
