"""The science's error classes name contract error types that exist (the science cannot import the contract)."""

from __future__ import annotations

import pytest

from manifoundation.contract import ErrorType
from manifoundation.core.errors import ScienceError, all_errors


@pytest.mark.parametrize("cls", all_errors(), ids=lambda c: c.__name__)
def test_every_science_error_names_a_contract_type(cls: type[ScienceError]) -> None:
    assert ErrorType.parse(cls.code) is not None, f"{cls.__name__}.code {cls.code!r} is not an ErrorType"


def test_the_tree_holds_the_errors_the_pipeline_raises() -> None:
    from manifoundation.core.geometry import InvalidPointCloud
    from manifoundation.core.network import CheckpointError
    from manifoundation.core.pipeline import InvalidInput, ModelUnavailable
    from manifoundation.core.robots import HandLoadError, UnknownHand

    for cls in (InvalidPointCloud, CheckpointError, InvalidInput, ModelUnavailable, HandLoadError, UnknownHand):
        assert cls in all_errors()
    assert issubclass(InvalidPointCloud, ValueError) and issubclass(UnknownHand, LookupError)
