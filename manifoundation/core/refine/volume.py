"""Mass properties of an object known only by its oriented points: the volume inside their winding number.

A convex hull overstates a concave object's volume and moves its centre of mass (a cabinet's, a mug's): the task
wrench is taken about the centre of mass, so a lift computed about the hull's centre asks for a torque the real
object does not need (an outside check measured a wrench cosine of 0.988 for such a lift). The occupied volume
is estimated on a grid over the points' bounding box, each cell filled by the points' generalised winding number
there, clipped to [0, 1] (`PointCloudField.winding_number`).
"""

from __future__ import annotations

import numpy as np

from manifoundation.core.geometry import MassProperties
from manifoundation.core.refine.field import PointCloudField

THIN_WALL = 2.0
GRID_CELLS = 16
"""Cells along the bounding box's longest side (5 mm for an 8 cm object; centre of mass within 1 mm of the
exact mesh's on third-party objects, where the hull's was 3-9 mm off)."""


def points_mass_properties(field: PointCloudField, density: float, cells: int = GRID_CELLS) -> MassProperties:
    """Mass, centre of mass (3,) and inertia (3, 3) about it, of the volume the points enclose at ``density``; of
    a shell of the points' surface when that volume is thinner than ``THIN_WALL`` disc radii on average (walls
    thinner than the point spacing: the winding number inside them is unreliable — a drawer's volume came out
    34 % short and its centre of mass 9 mm off; the area-weighted centroid of its points is 2 mm off)."""
    lo, hi = field.points.min(0), field.points.max(0)
    step = float((hi - lo).max()) / cells
    counts = np.maximum(np.ceil((hi - lo) / step).astype(int), 1)
    mid = 0.5 * (lo + hi)  # a grid centred on the box: an off-centre one biases the centre of mass by a cell
    axes = [c + (np.arange(k) - 0.5 * (k - 1)) * step for c, k in zip(mid, counts, strict=True)]
    grid = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    # the winding number as each cell's filled fraction: cells the surface cuts count in part (a 0/1 threshold
    # moved an L-shaped part's centre of mass by 1.9 mm on 5 mm cells)
    fill = np.clip(field.winding_number(grid), 0.0, 1.0)
    area = field.sample_area()  # (N,) the surface each point stands for
    thickness = float(fill.sum()) * step**3 / max(float(area.sum()), 1e-12)
    if thickness < THIN_WALL * field.disc_radius:
        return _shell(field.points, area, max(thickness, field.disc_radius), density)
    cell_mass = density * step**3 * fill
    mass = float(cell_mass.sum())
    com = (cell_mass[:, None] * grid).sum(axis=0) / mass
    r = grid - com
    # each cell as a small cube: its own inertia step²/6 · m about every axis, plus the parallel-axis term
    inertia = ((r**2).sum(1) * cell_mass).sum() * np.eye(3) - (cell_mass[:, None] * r).T @ r
    inertia += np.eye(3) * mass * step**2 / 6.0
    return MassProperties(mass, com, inertia)


def _shell(points: np.ndarray, area: np.ndarray, thickness: float, density: float) -> MassProperties:
    """A shell of the points' surface, ``thickness`` thick: each point a mass ρ a_j t at its place."""
    mass_j = density * thickness * area
    mass = float(mass_j.sum())
    com = (mass_j[:, None] * points).sum(axis=0) / mass
    r = points - com
    inertia = ((r**2).sum(1) * mass_j).sum() * np.eye(3) - (mass_j[:, None] * r).T @ r
    return MassProperties(mass, com, inertia)
