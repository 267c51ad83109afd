"""The object to manipulate: oriented point cloud, material, physical properties, region mask, joint."""

from __future__ import annotations

from enum import StrEnum
from typing import Literal

import numpy as np
from pydantic import Field, model_validator

from manifoundation.contract.common import (
    MAX_POINTS,
    MIN_POINTS,
    Faces,
    Mask,
    Points,
    Rows3,
    UnitVec3,
    Vec3,
    WireModel,
)


class Material(StrEnum):
    """Kind of object; decides which physical properties are meaningful."""

    RIGID = "rigid"
    ARTICULATED = "articulated"
    CLOTH = "cloth"
    ROPE = "rope"
    PLASTICINE = "plasticine"


# The network's six property channels (paper §III-A), in its order.
PROPERTY_NAMES = ("friction", "density", "stretch", "bending", "youngs_modulus", "poisson_ratio")

# Which properties each material may carry (paper: friction for all; density, stretch and bending for cloth;
# Young's modulus and Poisson's ratio for 1D and 3D deformables; density for rigid bodies' mass and inertia).
MATERIAL_PROPERTIES: dict[Material, frozenset[str]] = {
    Material.RIGID: frozenset({"friction", "density"}),
    Material.ARTICULATED: frozenset({"friction", "density"}),
    Material.CLOTH: frozenset({"friction", "density", "stretch", "bending"}),
    Material.ROPE: frozenset({"friction", "youngs_modulus", "poisson_ratio"}),
    Material.PLASTICINE: frozenset({"friction", "youngs_modulus", "poisson_ratio", "yield_stress"}),
}


class PhysicalProperties(WireModel):
    """Physical properties in SI units; leave out what does not apply to the material."""

    friction: float = Field(0.5, gt=0, le=5, description="Coulomb friction coefficient μ (dimensionless).")
    density: float | None = Field(None, gt=0, le=25_000, description="kg/m³ (rigid default: 500).")
    stretch: float | None = Field(None, gt=0, le=1e6, description="Cloth stretching stiffness, N/m.")
    bending: float | None = Field(None, gt=0, le=10, description="Cloth bending stiffness, N·m.")
    youngs_modulus: float | None = Field(None, gt=0, le=1e10, description="Young's modulus, Pa.")
    poisson_ratio: float | None = Field(None, ge=0, lt=0.5, description="Poisson's ratio (dimensionless).")
    yield_stress: float | None = Field(None, gt=0, le=1e8, description="Plasticine: von Mises yield stress, Pa.")

    def present(self) -> dict[str, float]:
        """The properties that were given, by name (the network's six, then yield_stress)."""
        names = (*PROPERTY_NAMES, "yield_stress")
        return {name: value for name in names if (value := getattr(self, name)) is not None}


class MeshIn(WireModel):
    """An optional triangle mesh of the object (used for exact collision checks)."""

    vertices: Rows3
    faces: Faces

    @model_validator(mode="after")
    def _faces_index_vertices(self) -> MeshIn:
        if len(self.vertices) < 4 or len(self.faces) < 4:
            raise ValueError("mesh needs at least 4 vertices and 4 faces")
        if self.faces.min() < 0 or self.faces.max() >= len(self.vertices):
            raise ValueError(f"faces index vertices outside 0..{len(self.vertices) - 1}")
        return self


class ArticulationJoint(WireModel):
    """The joint of an articulated object; ``part_mask`` marks the points of the moving part."""

    type: Literal["revolute", "prismatic"]
    axis: UnitVec3
    origin: Vec3 = Field(default_factory=lambda: np.zeros(3))
    part_mask: Mask


class ObjectIn(WireModel):
    """An object: N points (64 ≤ N ≤ 200 000), metres, with optional outward unit normals."""

    points: Points = Field(..., json_schema_extra={"minItems": MIN_POINTS, "maxItems": MAX_POINTS})
    normals: Points | None = None
    mesh: MeshIn | None = None
    material: Material = Material.RIGID
    properties: PhysicalProperties = Field(default_factory=PhysicalProperties)
    region_mask: Mask | None = Field(None, description="(N,) 0/1: 1 where contact is allowed; at least one 1.")
    joint: ArticulationJoint | None = None

    @property
    def num_points(self) -> int:
        """N, the number of points."""
        return int(self.points.shape[0])

    @model_validator(mode="after")
    def _consistent(self) -> ObjectIn:
        n = self.num_points
        if not MIN_POINTS <= n <= MAX_POINTS:
            raise ValueError(f"points: {n} points given, need {MIN_POINTS}..{MAX_POINTS}")
        with np.errstate(all="ignore"):
            centred = self.points - self.points.mean(axis=0)
        if not np.all(np.isfinite(centred)) or np.abs(centred).max() > 1e6:
            raise ValueError("points: coordinates beyond ±1000 km; points are in metres")
        spread = np.linalg.svd(centred, compute_uv=False)
        if spread[0] < 1e-9 or spread[1] < 1e-6 * spread[0]:
            raise ValueError("points: all points lie on one line (or coincide); an object needs a 2D or 3D extent")
        if self.normals is not None:
            if self.normals.shape != self.points.shape:
                raise ValueError(f"normals: shape {self.normals.shape} does not match points {self.points.shape}")
            lengths = np.linalg.norm(self.normals, axis=1)
            if np.any(lengths < 1e-6):
                raise ValueError(f"normals: zero-length normal at index {int(np.argmax(lengths < 1e-6))}")
            if np.any(np.abs(lengths - 1) > 1e-9):  # normalise once; a round trip changes nothing
                self.normals = self.normals / lengths[:, None]
        if self.region_mask is not None:
            if self.region_mask.shape != (n,):
                raise ValueError(f"region_mask: shape {self.region_mask.shape}, expected ({n},)")
            if not self.region_mask.any():
                raise ValueError("region_mask: all zero, no point may be touched")
        allowed = MATERIAL_PROPERTIES[self.material]
        extra = sorted(set(self.properties.present()) - allowed)
        if extra:
            raise ValueError(
                f"properties: {', '.join(extra)} not meaningful for material '{self.material.value}' "
                f"(allowed: {', '.join(sorted(allowed))})"
            )
        if self.material is Material.ARTICULATED:
            if self.joint is None:
                raise ValueError("joint: required for material 'articulated'")
            if self.joint.part_mask.shape != (n,):
                raise ValueError(f"joint.part_mask: shape {self.joint.part_mask.shape}, expected ({n},)")
            if not self.joint.part_mask.any():
                raise ValueError("joint.part_mask: all zero, the moving part has no points")
        elif self.joint is not None:
            raise ValueError(f"joint: only for material 'articulated', not '{self.material.value}'")
        return self
