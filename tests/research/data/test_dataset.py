"""Training batches: under a partial region mask only the valid grasps inside it are targets."""

from __future__ import annotations

import numpy as np

from research.data.dataset import Examples, make_batch


def _sphere(n: int = 200) -> np.ndarray:
    k = np.arange(n) + 0.5
    phi, theta = np.arccos(1 - 2 * k / n), np.pi * (1 + 5**0.5) * k
    return 0.05 * np.stack([np.cos(theta) * np.sin(phi), np.sin(theta) * np.sin(phi), np.cos(phi)], axis=1)


def _examples(mask: np.ndarray) -> Examples:
    points = _sphere()
    normals = points / np.linalg.norm(points, axis=1, keepdims=True)
    own = np.array([[0.05, 0.0, 0.0], [0.0, 0.05, 0.0]])  # the example's grasp: +x and +y
    other = np.array([[-0.05, 0.0, 0.0], [0.0, -0.05, 0.0]])  # another valid grasp: -x and -y
    contacts = np.full((1, 8, 2, 3), np.nan)
    contacts[0, 0], contacts[0, 1] = own, other
    n = len(points)
    return Examples(
        points=points[None], normals=normals[None], obj_index=np.zeros(1, dtype=np.int64),
        hand=np.array(["panda_gripper"]), split=np.array(["train"]), friction=np.array([0.5]),
        motion=np.zeros((1, n, 3)), heat=np.zeros((1, n)), force_map=np.zeros((1, n, 3)), mask=mask[None],
        extra={"set_contacts": contacts, "set_normals": contacts / 0.05, "set_forces": np.zeros_like(contacts),
               "set_count": np.array([2]), "object_scale": np.array([0.1])},
    )  # fmt: skip


def test_under_a_partial_mask_the_target_is_never_a_grasp_outside_it() -> None:
    points = _sphere()
    partial = make_batch(_examples(points[:, 0] > 0.0), np.zeros(1, dtype=np.int64), 0.2, np.random.default_rng(0))
    assert partial.set_valid[0].tolist() == [True] + [False] * 7  # the -x/-y grasp lies outside the +x half
    whole = np.ones(len(points), dtype=bool)
    picks = set()
    for seed in range(12):
        batch = make_batch(_examples(whole), np.zeros(1, dtype=np.int64), 0.2, np.random.default_rng(seed))
        assert batch.set_valid[0].tolist() == [True, True] + [False] * 6
        picks.add(int(np.argmin([float((batch.heat[0] - batch.set_heat[0, g]).abs().sum()) for g in range(2)])))
    assert picks == {0, 1}  # without a mask either valid grasp may be the target
