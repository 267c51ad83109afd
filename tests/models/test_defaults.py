"""The science's physical defaults are the wire contract's (written once each side; the science cannot import
the contract, so this test keeps them equal)."""

from __future__ import annotations

from clients.schemas import PhysicalProperties
from models.evaluation.refinement import DEFAULT_MU
from models.geometry.object import DEFAULT_DENSITY, DEFAULT_FRICTION


def test_default_friction_is_the_contracts() -> None:
    assert PhysicalProperties().friction == DEFAULT_FRICTION == DEFAULT_MU


def test_one_default_density() -> None:
    density = PhysicalProperties.model_fields["density"].default
    assert density is None or density == DEFAULT_DENSITY
