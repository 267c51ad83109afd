import numpy as np
import pytest

from manifoundation.core.deformable.materials import CLOTH_POISSON, RANGES, flex_parameters, sample_properties


def test_cloth_thickness_and_modulus_reproduce_both_stiffnesses() -> None:
    props = {"friction": 0.5, "density": 1000.0, "stretch": 2e3, "bending": 5e-5}
    p = flex_parameters("cloth", props, measure=0.25)
    nu = CLOTH_POISSON
    assert p.young * p.thickness / (1 - nu**2) == pytest.approx(2e3, rel=1e-9)
    assert p.young * p.thickness**3 / (12 * (1 - nu**2)) == pytest.approx(5e-5, rel=1e-9)
    assert p.mass == pytest.approx(1000.0 * p.thickness * 0.25)


def test_plasticine_yield_strain_is_stress_over_modulus() -> None:
    p = flex_parameters("plasticine", {"youngs_modulus": 1e6, "yield_stress": 2e4}, measure=1e-4)
    assert p.yield_strain == pytest.approx(0.02)
    assert p.young == 1e6


@pytest.mark.parametrize("material", sorted(RANGES))
def test_samples_stay_inside_the_documented_ranges(material: str) -> None:
    rng = np.random.default_rng(0)
    for _ in range(50):
        for name, value in sample_properties(material, rng).items():
            lo, hi, _ = RANGES[material][name]
            assert lo <= value <= hi


def test_rigid_is_not_a_deformable_material() -> None:
    with pytest.raises(ValueError, match="material"):
        flex_parameters("rigid", {}, 1.0)
