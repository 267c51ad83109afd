"""Cloth shapes: outlines (square, rectangle, disc, T-shirt, trousers, towel) remeshed into even triangles.

An outline is a polygon in the table plane; it is remeshed by a triangular lattice of spacing h (chosen for about
``target_vertices`` vertices) whose points at least h/2 inside the outline are kept, plus the outline resampled
every h; a Delaunay triangulation of those points, less the triangles whose centre lies outside the outline or
whose longest edge exceeds 1.6 h (across a concavity) and the slivers (area < 0.1 h², three points of a curved
outline), is the mesh. Sizes: the longest side is drawn in
``CLOTH_SIZE``.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from matplotlib.path import Path
from scipy.spatial import Delaunay

from manifoundation.core.deformable.body import DeformableBody
from manifoundation.core.deformable.materials import sample_properties

CLOTH_SIZE = (0.2, 0.5)  # m, longest side
LIFT = 0.004  # m: the cloth lies this high (its collision radius) above the table


def _square(rng: np.random.Generator) -> np.ndarray:
    return np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]], dtype=np.float64) / 2


def _rectangle(rng: np.random.Generator) -> np.ndarray:
    a = rng.uniform(0.45, 0.8) / 2
    return np.array([[-0.5, -a], [0.5, -a], [0.5, a], [-0.5, a]])


def _towel(rng: np.random.Generator) -> np.ndarray:
    a = rng.uniform(0.25, 0.4) / 2
    return np.array([[-0.5, -a], [0.5, -a], [0.5, a], [-0.5, a]])


def _disc(rng: np.random.Generator) -> np.ndarray:
    t = np.linspace(0, 2 * np.pi, 40, endpoint=False)
    return 0.5 * np.column_stack([np.cos(t), np.sin(t) * rng.uniform(0.7, 1.0)])


def _tshirt(rng: np.random.Generator) -> np.ndarray:
    w, s, n, h = rng.uniform(0.26, 0.34), rng.uniform(0.18, 0.26), rng.uniform(0.08, 0.12), rng.uniform(0.18, 0.26)
    pts = [(-w, -0.5), (w, -0.5), (w, 0.5 - h - 0.05), (w + s, 0.5 - h), (w + s * 0.8, 0.5 - 0.02),
           (n, 0.5), (-n, 0.5), (-w - s * 0.8, 0.5 - 0.02), (-w - s, 0.5 - h), (-w, 0.5 - h - 0.05)]
    return np.array(pts)


def _trousers(rng: np.random.Generator) -> np.ndarray:
    w, g, c = rng.uniform(0.28, 0.36), rng.uniform(0.04, 0.08), rng.uniform(0.25, 0.4)
    pts = [(-w, 0.5), (w, 0.5), (w + 0.04, -0.5), (g, -0.5), (0.0, 0.5 - c), (-g, -0.5), (-w - 0.04, -0.5)]
    return np.array(pts)


OUTLINES: dict[str, Callable[[np.random.Generator], np.ndarray]] = {
    "square": _square, "rectangle": _rectangle, "disc": _disc, "tshirt": _tshirt, "trousers": _trousers,
    "towel": _towel,
}  # fmt: skip
CLOTH_KINDS = tuple(OUTLINES)


def _segment_distance(points: np.ndarray, outline: np.ndarray) -> np.ndarray:
    """Distance (P,) of 2D points to a closed polygon's edges."""
    a, b = outline, np.roll(outline, -1, axis=0)
    ab = b - a
    t = np.clip(np.einsum("pkj,kj->pk", points[:, None] - a[None], ab) / np.einsum("kj,kj->k", ab, ab), 0, 1)
    closest = a[None] + t[..., None] * ab[None]
    distance: np.ndarray = np.linalg.norm(points[:, None] - closest, axis=-1).min(axis=1)
    return distance


def _resample(outline: np.ndarray, h: float) -> np.ndarray:
    out = []
    for a, b in zip(outline, np.roll(outline, -1, axis=0), strict=True):
        k = max(1, int(np.ceil(np.linalg.norm(b - a) / h)))
        out.append(a + (b - a) * (np.arange(k) / k)[:, None])
    return np.vstack(out)


def remesh(outline: np.ndarray, target_vertices: int = 200) -> tuple[np.ndarray, np.ndarray]:
    """Even triangles inside a 2D polygon: vertices (V, 2) and triangles (T, 3) (see the module doc)."""
    path = Path(outline)
    lo, hi = outline.min(0), outline.max(0)
    x, y = outline[:, 0], outline[:, 1]
    area = 0.5 * abs(float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1))))
    h = float(np.sqrt(2 * area / (np.sqrt(3) * target_vertices)))
    rows = []
    for i, y in enumerate(np.arange(lo[1], hi[1] + h, h * np.sqrt(3) / 2)):
        xs = np.arange(lo[0] + (i % 2) * h / 2, hi[0] + h, h)
        rows.append(np.column_stack([xs, np.full(len(xs), y)]))
    grid = np.vstack(rows)
    inside = path.contains_points(grid) & (_segment_distance(grid, outline) > 0.5 * h)
    pts = np.vstack([_resample(outline, h), grid[inside]])
    tri = Delaunay(pts).simplices
    centres = pts[tri].mean(axis=1)
    edges = np.linalg.norm(pts[tri] - pts[np.roll(tri, 1, axis=1)], axis=-1).max(axis=1)
    a, b, c = pts[tri[:, 0]], pts[tri[:, 1]], pts[tri[:, 2]]
    area = 0.5 * np.abs((b - a)[:, 0] * (c - a)[:, 1] - (b - a)[:, 1] * (c - a)[:, 0])
    tri = tri[path.contains_points(centres) & (edges < 1.6 * h) & (area > 0.1 * h * h)]
    used = np.unique(tri)
    remap = np.full(len(pts), -1)
    remap[used] = np.arange(len(used))
    return pts[used], remap[tri]


def make_cloth(kind: str, seed: int, properties: dict[str, float] | None = None, size: float | None = None,
               target_vertices: int = 200) -> DeformableBody:  # fmt: skip
    """A flat cloth of outline ``kind`` (one of `CLOTH_KINDS`) lying on the table, centred at the origin.

    Args:
        kind: outline name.
        seed: draws the outline's proportions, the size and (when ``properties`` is None) the properties.
        properties: cloth properties (default: sampled in `materials.RANGES`).
        size: longest side in metres (default: drawn in `CLOTH_SIZE`).
        target_vertices: about this many mesh vertices.
    """
    if kind not in OUTLINES:
        raise ValueError(f"kind: {kind!r} is not a cloth outline ({', '.join(CLOTH_KINDS)})")
    rng = np.random.default_rng(seed)
    outline = OUTLINES[kind](rng)
    outline = (outline - outline.mean(0)) / np.ptp(outline, axis=0).max()
    scale = float(rng.uniform(*CLOTH_SIZE)) if size is None else float(size)
    props = sample_properties("cloth", rng) if properties is None else dict(properties)
    xy, tri = remesh(outline * scale, target_vertices)
    vertices = np.column_stack([xy, np.full(len(xy), LIFT)])
    normals = np.tile([0.0, 0.0, 1.0], (len(xy), 1))
    return DeformableBody("cloth", kind, vertices, tri, np.arange(len(xy)), normals, props, seed)
