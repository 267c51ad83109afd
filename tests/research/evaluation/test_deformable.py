import numpy as np

from manifoundation.core.deformable.simulate import simulate
from research.data.deformable_generate import DeformableDataConfig
from research.evaluation.deformable import build_cases, evaluate_case


def test_ground_truth_replay_reaches_the_target_and_baselines_are_scored_on_the_same_case() -> None:
    [case] = build_cases("rope", "test_uo", 1, seed=0, data=DeformableDataConfig(seed=0))
    assert case.split == "test_uo" and case.target.shape == case.body.points.shape
    results = evaluate_case(case, ("random_motion", "ground_truth"), contacts=2, rng=np.random.default_rng(0))
    by_method = {r.method: r for r in results}
    assert by_method["ground_truth"].score.success  # the simulator is deterministic
    assert by_method["ground_truth"].score.mean_error == 0.0
    assert by_method["random_motion"].contacts == 2


def test_the_moving_points_baseline_reaches_a_rope_drag_that_spread_random_points_miss() -> None:
    """A rope dragged by one end: grasping the points that move most (with the target's motion there) reaches the
    target by the paper's metric in the simulator; spread random points with the same motions do worse."""
    cases = build_cases("rope", "test_uo", 2, seed=0, data=DeformableDataConfig(seed=0))
    scores = {"moving_target_motion": [], "random_target_motion": []}
    for case in cases:
        for r in evaluate_case(case, tuple(scores), contacts=2, rng=np.random.default_rng(0)):
            scores[r.method].append(r.score)
    assert all(s.success for s in scores["moving_target_motion"])
    mean = {m: float(np.mean([s.mean_error for s in v])) for m, v in scores.items()}
    assert mean["moving_target_motion"] < mean["random_target_motion"]



def test_readback_is_the_heads_own_motion_length_over_the_targets_at_its_contacts() -> None:
    from research.evaluation.deformable import motion_readback
    from research.evaluation.deformable_service import Proposal

    [case] = build_cases("rope", "test_uo", 1, seed=0, data=DeformableDataConfig(seed=0))
    displacement = case.target - case.body.points
    idx = np.array([0, len(displacement) // 2])
    points = case.body.points[idx]
    assert motion_readback(case, points, displacement[idx]) == 1.0
    assert np.isclose(motion_readback(case, points, 0.4 * displacement[idx]), 0.4)
    # the answer moves by the target's displacement; the head's own estimate (a short map) is what is read back
    short = lambda c: Proposal(points, displacement[idx], "network", 0.5 * displacement[idx])  # noqa: E731
    [result] = evaluate_case(case, ("network",), contacts=2, rng=np.random.default_rng(0), network=short)
    assert np.isclose(result.readback, 0.5)
    no_maps = lambda c: Proposal(points, displacement[idx], "network")  # noqa: E731
    [result] = evaluate_case(case, ("network",), contacts=2, rng=np.random.default_rng(0), network=no_maps)
    assert np.isnan(result.readback)


def test_the_heads_estimate_is_its_motion_map_over_its_heat_at_its_contacts() -> None:
    from research.evaluation.deformable_service import head_estimate

    heat = np.array([0.5, 0.02, 1.0])
    motion_map = np.array([[0.1, 0, 0], [0.0, 0.01, 0], [0, 0, 0.3]])
    got = head_estimate(heat, motion_map, np.array([0, 1, 2]))
    # the second point's heat is below the floor (0.1): its map is divided by the floor, not by 0.02
    assert np.allclose(got, [[0.2, 0, 0], [0, 0.1, 0], [0, 0, 0.3]])


def test_a_plasticine_case_is_a_fingertip_press_that_two_contacts_replay() -> None:
    [case] = build_cases("plasticine", "test_uo", 1, seed=0, data=DeformableDataConfig(seed=5))
    h = len(case.manipulation.contacts)
    assert 1 <= h <= 2  # one or two fingertip presses (issue 59)
    full, cut = evaluate_case(case, ("ground_truth", "ground_truth_cut"), contacts=2, rng=np.random.default_rng(0))
    assert full.contacts == h and full.score.success and full.score.closure == 1.0
    assert cut.contacts == h and cut.score.success and cut.score.mean_error == full.score.mean_error
    # the body left alone does not reach the target: the press left a dent
    still = simulate(case.body, np.zeros(0, dtype=np.int64), np.zeros((0, 3)))
    assert not still.reaches(case.body, case.target)


