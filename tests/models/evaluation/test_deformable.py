import numpy as np

from models.data.deformable_generate import DeformableDataConfig
from models.evaluation.deformable import build_cases, evaluate_case


def test_ground_truth_replay_reaches_the_target_and_baselines_are_scored_on_the_same_case() -> None:
    [case] = build_cases("rope", "test_uo", 1, seed=0, data=DeformableDataConfig(seed=0))
    assert case.split == "test_uo" and case.target.shape == case.body.points.shape
    results = evaluate_case(case, ("random_motion", "ground_truth"), contacts=2, rng=np.random.default_rng(0))
    by_method = {r.method: r for r in results}
    assert by_method["ground_truth"].score.success  # the simulator is deterministic
    assert by_method["ground_truth"].score.mean_error == 0.0
    assert by_method["random_motion"].contacts == 2
