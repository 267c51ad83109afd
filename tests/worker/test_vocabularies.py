"""The science accepts what the wire contract says, no more and no less: its methods, task kinds and materials are
the contract's (the worker resolves `auto` before the science runs). The core keeps its own tuples because it never
imports the contract (tests/test_layering.py); this test is the one place that ties them together."""

from __future__ import annotations

from manifoundation.contract import Material, Method
from manifoundation.contract.tasks import TASK_KINDS as WIRE_TASK_KINDS
from manifoundation.core.pipeline.types import MATERIALS, METHODS, TASK_KINDS


def test_the_science_takes_the_contracts_methods_but_auto() -> None:
    assert set(METHODS) == {m.value for m in Method} - {"auto"}


def test_the_science_takes_the_contracts_task_kinds_and_materials() -> None:
    assert set(TASK_KINDS) == set(WIRE_TASK_KINDS)
    assert set(MATERIALS) == {m.value for m in Material}
