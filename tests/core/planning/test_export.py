from manifoundation.core.planning.export import plan_to_dict, summary_lines


def test_export_has_the_wire_answer_fields(lifted):
    _, out = lifted
    data = plan_to_dict(out)
    assert len(data["positions"]) == len(out.poses) and len(data["steps"]) == len(out.poses) - 1
    assert data["steps"][1]["grasp"] == "kept" and data["steps"][0]["proposal"]["quality"]["success"]
    assert any("keep the grasp" in line for line in summary_lines(out))


def test_export_is_a_valid_wire_answer(lifted):
    """The exported plan validates as the draft wire answer (`manifoundation/contract/plans.py`): the same field
    names."""
    import numpy as np

    from manifoundation.contract.plans import PlanResult

    _, out = lifted
    result = PlanResult.model_validate({**plan_to_dict(out), "hand": "allegro"})
    assert result.steps[1].grasp == "kept" and result.steps[0].proposal is not None
    np.testing.assert_allclose(result.positions[-1], out.poses[-1].position)
    assert result.success and result.kept_share == 1.0
