import numpy as np

from manifoundation.core.deformable.metrics import (
    most_moving,
    paper_solid_success,
    shape_score,
    shortfall,
)


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


def _press(depth: float) -> tuple[np.ndarray, np.ndarray]:
    """A 1 m lattice block of 10 × 10 × 4 points (×2 to the normalised cube) whose top layer (100 points) is
    pressed down by ``depth`` m: start, target (400, 3)."""
    g, z = np.linspace(0.0, 1.0, 10), np.linspace(0.0, 1.0, 4)
    start = np.stack(np.meshgrid(g, g, z, indexing="ij"), axis=-1).reshape(-1, 3)
    target = start.copy()
    target[start[:, 2] == 1.0, 2] -= depth
    return start, target


def test_solid_reaching_the_target_exactly_passes() -> None:
    start, target = _press(0.1)
    score = shape_score("plasticine", start, target, target)
    assert score.success and score.closure == 1.0 and score.all_points and paper_solid_success(score)


def test_solid_sixty_percent_of_the_way_fails_the_closure() -> None:
    start, target = _press(0.055)  # 0.11 in the cube; a quarter of the points move, the mean distance is 0.0275
    score = shape_score("plasticine", start, target, start + 0.6 * (target - start))
    # the pressed points end 0.044 short in the cube: the selected term (< 0.05) holds, 40 % of the distance is open
    assert np.isclose(score.closure, 0.6) and np.isclose(score.top_mean_error, 0.044) and not score.success
    passing = shape_score("plasticine", start, target, start + 0.8 * (target - start))
    assert np.isclose(passing.closure, 0.8) and np.isclose(passing.top_mean_error, 0.022) and passing.success
    # … which the paper's all-points term (mean error < 0.005 in the cube) fails: the mean error is 0.0055
    assert np.isclose(passing.mean_error, 0.0055) and not passing.all_points and not paper_solid_success(passing)
    assert shortfall("plasticine", passing) <= 1.0 < shortfall("plasticine", score)


def test_solid_closing_the_mean_but_misplacing_the_most_moved_points_fails() -> None:
    start, target = _press(0.2)  # 0.4 in the cube, mean distance 0.1
    rollout = target.copy()
    rollout[start[:, 2] == 1.0, 0] += 0.03  # the pressed points land 0.03 m (0.06 in the cube) off sideways
    score = shape_score("plasticine", start, target, rollout)
    assert np.isclose(score.closure, 0.85)  # 1 − 0.015 / 0.1: closed enough…
    assert np.isclose(score.top_mean_error, 0.06) and not score.success  # …but the selected term fails


def test_solid_rule_is_scale_free() -> None:
    start, target = _press(0.055)
    for scale in (0.05, 1.0, 20.0):
        for share, ok in ((0.6, False), (0.8, True)):
            rollout = start + share * (target - start)
            score = shape_score("plasticine", scale * start, scale * target, scale * rollout)
            assert score.success is ok and np.isclose(score.closure, share)


def test_solid_doing_nothing_or_diverging_fails() -> None:
    start, target = _press(0.1)
    still = shape_score("plasticine", start, target, start)
    assert still.closure == 0.0 and not still.success
    assert not shape_score("plasticine", start, target, np.full_like(start, np.nan)).success


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
