"""The science mirrors the contract's enums and limits without importing it (docs/layering.md): the copies equal
the contract's, so a limit changed in the contract cannot leave the science (or a front end) on the old one."""

from __future__ import annotations

from manifoundation.contract import MAX_PROPOSALS, Material, Method
from manifoundation.contract.plans import PlanOptions
from manifoundation.contract.requests import SynthesisOptions
from manifoundation.contract.tasks import TASK_KINDS
from manifoundation.core.pipeline import types as science


def test_the_science_copies_equal_the_contract() -> None:
    assert science.MAX_PROPOSALS == MAX_PROPOSALS
    assert set(science.METHODS) == {m.value for m in Method} - {Method.AUTO.value}
    assert set(science.MATERIALS) == {m.value for m in Material}
    assert set(science.TASK_KINDS) == set(TASK_KINDS)


def test_every_num_proposals_range_is_the_contract_constant() -> None:
    from manifoundation.core.planning.types import PlanOptions as SciencePlanOptions
    from manifoundation.core.planning.validate import InvalidPlan, check_options

    for model, field in ((SynthesisOptions, "num_proposals"), (SynthesisOptions, "stop_after_verified"),
                         (PlanOptions, "num_proposals")):  # fmt: skip
        upper = [m.le for m in model.model_fields[field].metadata if hasattr(m, "le")]
        assert upper == [MAX_PROPOSALS], (model, field, upper)
    check_options(SciencePlanOptions(num_proposals=MAX_PROPOSALS))
    try:
        check_options(SciencePlanOptions(num_proposals=MAX_PROPOSALS + 1))
    except InvalidPlan as exc:
        assert str(MAX_PROPOSALS) in str(exc)
    else:
        raise AssertionError("the science accepted more proposals than the contract allows")
