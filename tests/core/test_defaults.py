"""The science's physical defaults are the wire contract's (written once each side; the science cannot import
the contract, so this test keeps them equal)."""

from __future__ import annotations

from manifoundation.contract import PhysicalProperties
from manifoundation.core.geometry.object import DEFAULT_DENSITY, DEFAULT_FRICTION
from research.evaluation.refinement import DEFAULT_MU


def test_default_friction_is_the_contracts() -> None:
    assert PhysicalProperties().friction == DEFAULT_FRICTION == DEFAULT_MU


def test_one_default_density() -> None:
    density = PhysicalProperties.model_fields["density"].default
    assert density is None or density == DEFAULT_DENSITY
