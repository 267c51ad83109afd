"""Deformable materials: their properties in the contract's units, the ranges we sample, and MuJoCo's parameters.

Units and ranges (the data generator samples inside them; log-uniform where marked):

| material | property | unit | range |
|---|---|---|---|
| cloth | friction | – | 0.3 – 1.0 |
| cloth | density | kg/m³ | 300 – 1 500 |
| cloth | stretch (membrane stiffness k_s = E t / (1 − ν²)) | N/m | 3·10² – 3·10⁴ (log) |
| cloth | bending (plate stiffness D = E t³ / (12 (1 − ν²))) | N·m | 10⁻⁶ – 10⁻³ (log); a card ≈ 10⁻² |
| rope | friction | – | 0.3 – 1.0 |
| rope | youngs_modulus | Pa | 10³ – 10⁶ (log); a stick ≈ 10⁹ |
| rope | poisson_ratio | – | 0.2 – 0.45 |
| plasticine | friction | – | 0.3 – 1.0 |
| plasticine | youngs_modulus | Pa | 3·10⁵ – 3·10⁶ (log) |
| plasticine | poisson_ratio | – | 0.3 – 0.45 |
| plasticine | yield_stress (von Mises) | Pa | 5·10³ – 5·10⁴ (log) |

MuJoCo's flex elasticity takes Young's modulus E, Poisson's ratio ν and, for a shell, a thickness t. A cloth's
two stiffnesses give both: t = √(12 D / k_s) and E = k_s (1 − ν²) / t with ν = ``CLOTH_POISSON``; its areal mass is
density · t. MuJoCo's yield is a strain, so plasticine's yield stress becomes σ_y / E. A rope has no density in
the contract: ``ROPE_DENSITY`` and ``ROPE_RADIUS`` are fixed.

The rope's range is for its 1 cm rod (`manifoundation.core.deformable.rope`): dragged by its middle, a 60 cm rope at 10³
Pa leaves both ends in place, at 10⁵ Pa both ends follow by 8-10 cm, at 10⁷ Pa and above it moves like a stick.
Plasticine's ranges were chosen by simulation (docs/deformables.md): below E ≈ 3·10⁵ Pa with yield ≈ 2·10³ Pa an
8 cm body keeps flowing after a press is released; above yield ≈ 10⁵ Pa it springs back (elastic).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

MATERIALS = ("cloth", "rope", "plasticine")
CLOTH_POISSON = 0.3
ROPE_DENSITY = 1100.0  # kg/m³ (nylon/cotton cord)
ROPE_RADIUS = 0.005  # m
PLASTICINE_DENSITY = 1500.0  # kg/m³
MIN_YIELD_STRAIN = 1e-4

# property → (low, high, log-uniform)
RANGES: dict[str, dict[str, tuple[float, float, bool]]] = {
    "cloth": {
        "friction": (0.3, 1.0, False),
        "density": (300.0, 1500.0, False),
        "stretch": (3e2, 3e4, True),
        "bending": (1e-6, 1e-3, True),
    },
    "rope": {
        "friction": (0.3, 1.0, False),
        "youngs_modulus": (1e3, 1e6, True),
        "poisson_ratio": (0.2, 0.45, False),
    },
    "plasticine": {
        "friction": (0.3, 1.0, False),
        "youngs_modulus": (3e5, 3e6, True),
        "poisson_ratio": (0.3, 0.45, False),
        "yield_stress": (5e3, 5e4, True),
    },
}

# The paper's property figure asks for a card (a stiff square) and a stick (a stiff cylinder): `STIFF_RANGES`
# stretches cloth and rope ranges to reach them (data sets made with `--stiff`).
STIFF_RANGES: dict[str, dict[str, tuple[float, float, bool]]] = {
    **RANGES,
    "cloth": {**RANGES["cloth"], "stretch": (3e2, 1e5, True), "bending": (1e-6, 1e-2, True)},
    "rope": {**RANGES["rope"], "youngs_modulus": (1e3, 1e9, True)},
}

# The two ends of `STIFF_RANGES`' stiffnesses, where the figure's members sit (a handkerchief and a card, a rope
# and a stick). Drawn uniformly in log over the whole range, a body lands near the card in about 1 of 25 draws;
# `--stiff-ends` draws some bodies' stiffnesses inside one end instead (`sample_stiff_end`).
STIFF_ENDS: dict[str, tuple[dict[str, tuple[float, float, bool]], dict[str, tuple[float, float, bool]]]] = {
    "cloth": ({"stretch": (3e2, 3e3, True), "bending": (1e-6, 1e-4, True)},
              {"stretch": (3e4, 1e5, True), "bending": (1e-3, 1e-2, True)}),
    "rope": ({"youngs_modulus": (1e3, 1e5, True)}, {"youngs_modulus": (1e8, 1e9, True)}),
}  # fmt: skip

DEFAULTS: dict[str, dict[str, float]] = {
    "cloth": {"friction": 0.6, "density": 800.0, "stretch": 3e3, "bending": 3e-5},
    "rope": {"friction": 0.6, "youngs_modulus": 3e4, "poisson_ratio": 0.3},
    "plasticine": {"friction": 0.8, "youngs_modulus": 1e6, "poisson_ratio": 0.4, "yield_stress": 2e4},
}


@dataclass(frozen=True)
class FlexParameters:
    """What MuJoCo's ``<flexcomp>`` needs: E (Pa), ν, shell thickness t (m, cloth), yield strain, friction, mass."""

    young: float
    poisson: float
    thickness: float
    yield_strain: float
    friction: float
    mass: float


Ranges = dict[str, dict[str, tuple[float, float, bool]]]


def sample_properties(material: str, rng: np.random.Generator, ranges: Ranges = RANGES) -> dict[str, float]:
    """Random properties of ``material`` inside ``ranges`` (`RANGES` or `STIFF_RANGES`)."""
    out = {}
    for name, (lo, hi, log) in ranges[check_material(material)].items():
        out[name] = float(np.exp(rng.uniform(np.log(lo), np.log(hi)))) if log else float(rng.uniform(lo, hi))
    return out


def sample_stiff_end(material: str, rng: np.random.Generator, end: int | None = None) -> dict[str, float]:
    """Stiffnesses of ``material`` drawn in its `STIFF_ENDS` ``end`` (0: soft, 1: stiff; None: either, with equal
    chance); {} for plasticine, which has no ends."""
    ends = STIFF_ENDS.get(check_material(material))
    if ends is None:
        return {}
    return sample_properties(material, rng, {material: ends[int(rng.integers(2)) if end is None else end]})


def check_material(material: str) -> str:
    """``material`` if it is deformable, else ValueError naming it."""
    if material not in MATERIALS:
        raise ValueError(f"material: {material!r} is not deformable (one of {', '.join(MATERIALS)})")
    return material


def with_defaults(material: str, properties: dict[str, float]) -> dict[str, float]:
    """``properties`` completed with the material's `DEFAULTS` (only the names the material uses)."""
    base = DEFAULTS[check_material(material)]
    return {name: float(properties.get(name, value)) for name, value in base.items()}


def flex_parameters(material: str, properties: dict[str, float], measure: float) -> FlexParameters:
    """MuJoCo parameters of a body of ``material``.

    Args:
        material: cloth, rope or plasticine.
        properties: contract properties (missing ones take `DEFAULTS`).
        measure: the body's area (cloth, m²), length (rope, m) or volume (plasticine, m³).

    Returns:
        The flex parameters (mass from the measure and the density).
    """
    p = with_defaults(material, properties)
    mu = p["friction"]
    if material == "cloth":
        thickness = float(np.sqrt(12.0 * p["bending"] / p["stretch"]))
        young = p["stretch"] * (1.0 - CLOTH_POISSON**2) / thickness
        return FlexParameters(young, CLOTH_POISSON, thickness, 0.0, mu, p["density"] * thickness * measure)
    if material == "rope":
        mass = (
            ROPE_DENSITY * (2 * ROPE_RADIUS) ** 2 * measure
        )  # square cross-section (manifoundation.core.deformable.rope)
        return FlexParameters(p["youngs_modulus"], p["poisson_ratio"], 0.0, 0.0, mu, float(mass))
    strain = max(p["yield_stress"] / p["youngs_modulus"], MIN_YIELD_STRAIN)
    return FlexParameters(
        p["youngs_modulus"], p["poisson_ratio"], 0.0, float(strain), mu, PLASTICINE_DENSITY * measure
    )
