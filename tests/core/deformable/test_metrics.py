import numpy as np

from manifoundation.core.deformable.metrics import most_moving, shape_score


def _square(n: int = 100) -> np.ndarray:
    g = np.linspace(-0.5, 0.5, 10)
    x, y = np.meshgrid(g, g)
    return np.column_stack([x.ravel(), y.ravel(), np.zeros(n)])


def test_exact_rollout_succeeds_for_every_material() -> None:
    start = _square()
    target = start + np.array([0.1, 0.0, 0.0])
    for material in ("cloth", "rope", "plasticine"):
        assert shape_score(material, start, target, target).success


def test_cloth_threshold_on_the_normalised_cube() -> None:
    start = _square()  # side 1 m → ×2 to the 2 m cube
    target = start.copy()
    near = target + np.array([0.12, 0, 0])  # 0.24 normalised: under 0.3 everywhere
    far = target + np.array([0.2, 0, 0])  # 0.4 normalised: every point over 0.3
    assert shape_score("cloth", start, target, near).success
    score = shape_score("cloth", start, target, far)
    assert not score.success and score.top_fraction_over == 1.0


def test_cloth_fails_when_one_top_mover_is_off_by_more_than_half() -> None:
    start = _square()
    target = start.copy()
    target[0, 2] += 0.5  # the one point that moves: among the 50 most-moving
    rollout = target.copy()
    rollout[0, 2] -= 0.3  # 0.6 in the normalised cube
    assert not shape_score("cloth", start, target, rollout).success
    rollout[0, 2] += 0.1  # 0.4: over 0.3 but only 1 of 50
    assert shape_score("cloth", start, target, rollout).success


def test_solid_threshold_mean_half_centimetre() -> None:
    start = _square()
    target = start.copy()
    assert shape_score("plasticine", start, target, target + 0.002).success is False  # 0.4 cm·√3 ≈ 0.69 cm
    assert shape_score("plasticine", start, target, target + np.array([0.002, 0, 0])).success  # 0.4 cm


def test_a_slide_judges_every_point_not_the_fifty_round_off_picks() -> None:
    rng = np.random.default_rng(0)
    start = rng.uniform(0, 1, size=(200, 3))
    d = np.array([0.3, 0.1, 0.0])
    np.testing.assert_array_equal(np.sort(most_moving(start, start + d, 50)), np.arange(200))
    rollout = start + d
    rollout[:60] += [0.2, 0.0, 0.0]  # 60 of 200 points 0.4 off in the normalised cube: > 0.3, < 0.5
    first = shape_score("rope", start, start + d, rollout)
    again = shape_score("rope", start, start + d + rng.normal(scale=1e-15, size=start.shape), rollout)
    assert (first.success, first.top_fraction_over) == (again.success, again.top_fraction_over)
    assert first.top_fraction_over == 0.3 and first.success
    moved = np.linalg.norm(rng.normal(size=(200, 3)), axis=1)[:, None] * d
    assert len(most_moving(start, start + moved, 50)) == 50  # no ties: the fifty
