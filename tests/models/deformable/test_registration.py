import numpy as np

from models.deformable.registration import transport_motion


def test_a_shuffled_translation_is_recovered_exactly() -> None:
    rng = np.random.default_rng(0)
    start = rng.uniform(-0.1, 0.1, size=(200, 3))
    motion = np.array([0.01, 0.0, -0.005])  # smaller than the points' spacing: the assignment is the identity
    target = (start + motion)[rng.permutation(200)]
    np.testing.assert_allclose(transport_motion(start, target), np.tile(motion, (200, 1)), atol=1e-12)


def test_fewer_targets_than_points_still_give_every_point_a_motion() -> None:
    rng = np.random.default_rng(1)
    start = rng.uniform(-0.1, 0.1, size=(100, 3))
    target = start[:60] + 0.001
    out = transport_motion(start, target)
    assert out.shape == (100, 3) and np.all(np.isfinite(out))
