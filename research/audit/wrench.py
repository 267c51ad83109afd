"""Wrenches, friction cones and force closure of our own (numpy + scipy).

Sign convention: ``n`` is the object's OUTWARD unit normal at a contact, and a fingertip pushes on the object
along ``−n``: a force ``f`` is in the Coulomb cone when its normal component ``f·(−n) ≥ 0`` and its tangential
part ``‖f − (f·n) n‖ ≤ μ · f·(−n)``.

Wrenches are scaled: ``w = [f, (p − c) × f / L]`` (6,), with ``c`` the object's centre and ``L`` a
characteristic length, so that forces (N) and torques (N·m / m) are commensurate.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import ConvexHull, QhullError

CLOSURE_SIDES = 8
FRICTION_SLACK = 1e-6


def contact_wrenches(points: np.ndarray, forces: np.ndarray, centre: np.ndarray, length: float) -> np.ndarray:
    """Scaled wrench of each contact force about ``centre``.

    Args:
        points: (m, 3) contact points.
        forces: (m, 3) forces applied on the object.
        centre: (3,) reference point.
        length: characteristic length dividing the torques.

    Returns:
        (m, 6) ``[f, (p − c) × f / L]``.
    """
    arms = np.asarray(points, dtype=np.float64) - np.asarray(centre, dtype=np.float64)
    forces = np.asarray(forces, dtype=np.float64)
    return np.concatenate([forces, np.cross(arms, forces) / length], axis=1)


def scaled_wrench(wrench: np.ndarray, length: float) -> np.ndarray:
    """A physical wrench ``[F (N), τ (N·m)]`` (6,) in the scaled form ``[F, τ / L]``."""
    w = np.asarray(wrench, dtype=np.float64).copy()
    w[3:] /= length
    return w


def cosine(a: np.ndarray, b: np.ndarray) -> float:
    """Cosine of the angle between two vectors (0 when either is zero)."""
    na, nb = float(np.linalg.norm(a)), float(np.linalg.norm(b))
    return 0.0 if na == 0.0 or nb == 0.0 else float(np.dot(a, b) / (na * nb))


def friction_components(force: np.ndarray, normal: np.ndarray) -> tuple[float, float]:
    """Normal and tangential parts of a force at a contact.

    Args:
        force: (3,) force on the object.
        normal: (3,) outward unit normal of the object.

    Returns:
        ``(f·(−n), ‖f − (f·n) n‖)``: the pushing (normal) force and the tangential force magnitude.
    """
    n = np.asarray(normal, dtype=np.float64) / np.linalg.norm(normal)
    f = np.asarray(force, dtype=np.float64)
    along = float(np.dot(f, n))
    return -along, float(np.linalg.norm(f - along * n))


def in_cone(force: np.ndarray, normal: np.ndarray, mu: float, slack: float = FRICTION_SLACK) -> bool:
    """Whether ``force`` lies in the friction cone (pushing, tangential ≤ μ · normal), with relative slack."""
    fn, ft = friction_components(force, normal)
    scale = float(np.linalg.norm(force))
    return fn >= -slack * scale and ft <= mu * fn + slack * scale


def tangent_basis(normal: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit vectors orthogonal to ``normal`` and to each other."""
    n = np.asarray(normal, dtype=np.float64) / np.linalg.norm(normal)
    helper = np.array([1.0, 0.0, 0.0]) if abs(n[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    t1 = np.cross(n, helper)
    t1 /= np.linalg.norm(t1)
    return t1, np.cross(n, t1)


def pyramid_edges(normal: np.ndarray, mu: float, sides: int = CLOSURE_SIDES) -> np.ndarray:
    """Edges of the friction pyramid inscribed in the cone at a contact (pushing along ``−n``).

    Args:
        normal: (3,) outward unit normal.
        mu: friction coefficient.
        sides: number of edges.

    Returns:
        (sides, 3) edge forces ``−n + μ (cos θ_k t1 + sin θ_k t2)`` (unit normal component).
    """
    n = np.asarray(normal, dtype=np.float64) / np.linalg.norm(normal)
    t1, t2 = tangent_basis(n)
    theta = 2 * np.pi * np.arange(sides) / sides
    edges: np.ndarray = -n + mu * (np.cos(theta)[:, None] * t1 + np.sin(theta)[:, None] * t2)
    return edges


def primitive_wrenches(
    points: np.ndarray, normals: np.ndarray, mu: float, centre: np.ndarray, length: float, sides: int = CLOSURE_SIDES
) -> np.ndarray:
    """(m · sides, 6) scaled wrenches of every pyramid edge at every contact."""
    rows = []
    for p, n in zip(np.asarray(points, dtype=np.float64), np.asarray(normals, dtype=np.float64), strict=True):
        edges = pyramid_edges(n, mu, sides)
        rows.append(contact_wrenches(np.repeat(p[None], sides, axis=0), edges, centre, length))
    return np.concatenate(rows, axis=0) if rows else np.zeros((0, 6))


def closure_epsilon(
    points: np.ndarray, normals: np.ndarray, mu: float, centre: np.ndarray, length: float, sides: int = CLOSURE_SIDES,
    torsion: float = 0.0,
) -> float:
    """Distance from the origin to the boundary of the convex hull of the primitive wrenches.

    Positive when the origin is strictly inside the hull (force closure with the linearised cones): it is then
    the Ferrari–Canny ε of edges with unit normal component. 0 when the origin is on or outside the hull, or
    when the wrenches do not span the 6-D wrench space (fewer contacts than closure needs).

    Args:
        points: (m, 3) contact points.
        normals: (m, 3) outward unit normals.
        mu: friction coefficient.
        centre: (3,) torque reference point.
        length: torque scale.
        sides: pyramid edges per contact.
        torsion: soft-finger contacts (m): each also resists a moment about its normal of up to ``torsion`` × its
            normal force (two primitives ±, at unit normal force); 0: point contacts.

    Returns:
        ε ≥ 0.
    """
    w = primitive_wrenches(points, normals, mu, centre, length, sides)
    if torsion > 0:
        n = np.asarray(normals, dtype=np.float64)
        n = n / np.linalg.norm(n, axis=1, keepdims=True)
        push = contact_wrenches(np.asarray(points, dtype=np.float64), -n, centre, length)  # (m, 6)
        spin = np.hstack([np.zeros_like(n), torsion * n / length])
        w = np.vstack([w, push + spin, push - spin])
    if w.shape[0] < 7 or np.linalg.matrix_rank(w, tol=1e-9) < 6:
        return 0.0
    try:
        hull = ConvexHull(w)
    except QhullError:
        return 0.0
    # facets: a·x + b ≤ 0 inside, ‖a‖ = 1; the origin's distance to facet k is −b_k
    return max(0.0, float(np.min(-hull.equations[:, -1])))
