import numpy as np

from manifoundation.core.deformable.registration import transport_motion


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


def test_registration_recovers_a_rotated_sheet_that_transport_alone_mismatches() -> None:
    g = np.linspace(-0.1, 0.1, 12)
    x, y = np.meshgrid(g, g)
    start = np.column_stack([x.ravel(), y.ravel(), np.zeros(144)])
    a = np.deg2rad(20.0)
    rot = np.array([[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1]])
    truth = start @ rot.T - start
    target = (start + truth)[np.random.default_rng(0).permutation(144)]
    assert np.mean(np.linalg.norm(transport_motion(start, target, method="ot") - truth, axis=1) < 1e-9) < 0.1
    np.testing.assert_allclose(transport_motion(start, target), truth, atol=1e-9)  # CPD first: every point
