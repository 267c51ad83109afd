"""Physical-property encoder: one MLP ψ_i: R → R^10 per property, masked mean pooling (paper §III-A).

The property order is a fixed contract shared with the wire schema; missing properties are masked out of the
mean. Raw values span many orders of magnitude (Young's modulus ~1e3–1e9 Pa), so each is first mapped by a
fixed transform (:data:`PROPERTY_TRANSFORMS`) into roughly unit range.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

import torch
from torch import nn

PROPERTY_NAMES: tuple[str, ...] = (
    "friction",  # Coulomb friction coefficient μ (all objects)
    "density",  # kg/m^3 (or areal density for cloth, as the data set stores it)
    "stretch",  # cloth stretching (elasticity) stiffness
    "bending",  # cloth bending stiffness
    "youngs_modulus",  # Pa (1D/3D deformables)
    "poisson_ratio",  # dimensionless, [0, 0.5)
)

# How each raw value enters ψ_i: "linear" as is, "log10" as log10(max(v, 1e-12)).
PROPERTY_TRANSFORMS: dict[str, str] = {
    "friction": "linear",
    "density": "log10",
    "stretch": "log10",
    "bending": "log10",
    "youngs_modulus": "log10",
    "poisson_ratio": "linear",
}


def property_vector(properties: Mapping[str, float]) -> tuple[list[float], list[bool]]:
    """Transformed values and presence flags in :data:`PROPERTY_NAMES` order.

    Raises:
        ValueError: an unknown name, or a value that is not finite.
    """
    unknown = set(properties) - set(PROPERTY_NAMES)
    if unknown:
        raise ValueError(f"unknown physical properties {sorted(unknown)}; known: {list(PROPERTY_NAMES)}")
    values, present = [], []
    for name in PROPERTY_NAMES:
        if name not in properties:
            values.append(0.0)
            present.append(False)
            continue
        v = float(properties[name])
        if not math.isfinite(v):
            raise ValueError(f"physical property {name!r} is not finite: {v}")
        values.append(math.log10(max(v, 1e-12)) if PROPERTY_TRANSFORMS[name] == "log10" else v)
        present.append(True)
    return values, present


def property_tensors(batch: Sequence[Mapping[str, float]]) -> tuple[torch.Tensor, torch.Tensor]:
    """Stack a batch of property dicts into values (B, 6) float32 and mask (B, 6) bool."""
    rows = [property_vector(p) for p in batch]
    values = torch.tensor([r[0] for r in rows], dtype=torch.float32).view(len(rows), len(PROPERTY_NAMES))
    mask = torch.tensor([r[1] for r in rows], dtype=torch.bool).view(len(rows), len(PROPERTY_NAMES))
    return values, mask


class PropertyEncoder(nn.Module):
    """Γ = MMP(ψ_1(γ_1), ..., ψ_6(γ_6)) ∈ R^out_dim.

    The paper applies ψ_i per point; our properties are per object, so Γ is computed once per object and
    broadcast to its points (identical result). An object with no property present gets Γ = 0.
    """

    def __init__(self, hidden: int = 32, out_dim: int = 10) -> None:
        super().__init__()
        self.mlps = nn.ModuleList(
            nn.Sequential(nn.Linear(1, hidden), nn.ReLU(), nn.Linear(hidden, out_dim)) for _ in PROPERTY_NAMES
        )
        self.out_dim = out_dim

    def forward(self, values: torch.Tensor, mask: torch.Tensor) -> torch.Tensor:
        """Args: values (B, 6), mask (B, 6) bool. Returns Γ (B, out_dim)."""
        feats = torch.stack([mlp(values[:, i : i + 1]) for i, mlp in enumerate(self.mlps)], dim=1)
        m = mask.to(feats.dtype).unsqueeze(-1)
        return (feats * m).sum(dim=1) / m.sum(dim=1).clamp_min(1.0)
