"""Every valid grasp of an example: the grasps of the same object and hand that can produce its motion.

An example is one sampled grasp with random forces, and its target motion follows from their wrench. Most
motions can be produced by several of the grasps sampled for the same (object, hand): a heatmap regressed onto
the one that happened to make the example averages over them into a flat map (measured on the round-2 weights:
peaks at 0.3-0.4, the top point in the example's own contact region in 23 % of validation examples). So each
example carries the set of grasps that can produce its motion, with forces that do, and training rewards
hitting any one of them (`manifoundation.core.network.loss.set_heat_loss`).

A grasp g can produce an example's task when a linear programme is feasible: forces in 8-sided pyramids
inscribed in the friction cones (μ of the example), each normal force ≤ 1 (the refinement's bound), giving the
example's unit scaled wrench (rigid) or its joint-space effort (articulated, `manifoundation.core.refine.wrench`). The
pyramid is inside the cone, so a feasible programme is a feasible grasp. The example's own grasp is always in
its set (its forces are the label's). Grasps are those of the same shard, object and hand: the rows of the
examples' contact tables.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy.optimize import linprog, nnls

from manifoundation.core.refine.grasp import grasp_maps, tangents
from manifoundation.core.refine.wrench import articulated_task
from research.data.labels import heat_and_force

GraspRows = np.ndarray | Sequence[np.ndarray]
"""G grasps' rows: an array (G, C, 3) with NaN rows padding, or G arrays (C_g, 3)."""

PYRAMID_EDGES = 8
MAX_SET = 32  # grasps kept per example (its own first, then the feasible ones by grasp index), unless the shard says
REGION_HEAT = 0.5  # a point is in a grasp's contact region where the grasp's heat there is at least this
CONE_RESIDUAL = 1e-6  # relative: the task lies outside the grasp's pyramids when no λ ≥ 0 comes closer than this


def pyramid_edges(normals: np.ndarray, mu: float) -> np.ndarray:
    """(m, E, 3) edges of the inscribed friction pyramids, each with unit normal part (pointing inwards)."""
    t1, t2 = tangents(normals)
    ang = np.linspace(0.0, 2 * np.pi, PYRAMID_EDGES, endpoint=False)
    tang = np.cos(ang)[None, :, None] * t1[:, None] + np.sin(ang)[None, :, None] * t2[:, None]
    result: np.ndarray = -normals[:, None, :] + mu * tang
    return result


def pyramid_programme(
    contacts: np.ndarray, normals: np.ndarray, mu: float, centre: np.ndarray, length: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The parts of a linear programme over the friction pyramids' edge weights λ (m·E of them, ≥ 0).

    Returns:
        edges: (m, E, 3) the pyramids' edges (:func:`pyramid_edges`).
        wrench: (6, m·E) the scaled wrench ``Σ G_i f_i`` of unit weights (``wrench @ λ``).
        normal: (m, m·E) each contact's normal force (``normal @ λ``: the edges' normal parts are 1).
    """
    m = len(contacts)
    edges = pyramid_edges(normals, mu)
    g = grasp_maps(contacts, centre, length)  # (m, 6, 3)
    wrench = np.einsum("mij,mej->ime", g, edges).reshape(6, m * PYRAMID_EDGES)
    return edges, wrench, np.kron(np.eye(m), np.ones((1, PYRAMID_EDGES)))


def pyramid_forces(weights: np.ndarray, edges: np.ndarray) -> np.ndarray:
    """Forces (m, 3) of edge weights (m·E,) on ``edges`` (m, E, 3)."""
    forces: np.ndarray = np.einsum("me,mej->mj", weights.reshape(edges.shape[:2]), edges)
    return forces


def feasible_forces(
    contacts: np.ndarray, normals: np.ndarray, mu: float, rows: np.ndarray, target: np.ndarray, centre: np.ndarray,
    length: float,
) -> np.ndarray | None:  # fmt: skip
    """Forces (m, 3) at ``contacts`` with ``rows @ Σ G_i f_i = target``, or None when the programme is infeasible.

    Args:
        contacts, normals: (m, 3) contact points and outward normals.
        mu: friction coefficient.
        rows: (r, 6) task rows on the scaled wrench (identity for a rigid motion, P^J for a joint).
        target: (r,) the task's value.
        centre, length: the object's centre of mass and characteristic length (the scaled wrench's).
    """
    m = len(contacts)
    edges, wrench, normal = pyramid_programme(contacts, normals, mu, centre, length)
    task = rows @ wrench
    if _outside_cone(task, target):
        return None
    res = linprog(
        np.ones(m * PYRAMID_EDGES), A_ub=normal, b_ub=np.ones(m), A_eq=task, b_eq=target, bounds=(0, None),
        method="highs",
    )  # fmt: skip
    if res.status != 0:
        return None
    return pyramid_forces(res.x, edges)


def _outside_cone(task: np.ndarray, target: np.ndarray) -> bool:
    """Whether no λ ≥ 0 gives ``task @ λ = target`` (r, n), (r,): the programme is then infeasible whatever the
    bound on the normal forces. Non-negative least squares (≈ 20 µs) settles most of an object's grasp pairs —
    79 % of all of them in the data — before the programme (≈ 1.3 ms); an unconverged solve settles nothing."""
    try:
        _, residual = nnls(task, target)
    except RuntimeError:
        return False
    return bool(residual > CONE_RESIDUAL * max(1.0, float(np.linalg.norm(target))))


@dataclass
class GraspSets:
    """Per example, its valid grasps (own first), padded to the shard's set size (:data:`MAX_SET` unless its
    ``max_set`` says otherwise) grasps of ``MAX_CONTACTS`` contacts.

    Attributes:
        contacts, normals, forces: (E, G, C, 3), NaN where padded.
        count: (E,) valid grasps per example (≥ 1).
    """

    contacts: np.ndarray
    normals: np.ndarray
    forces: np.ndarray
    count: np.ndarray


def _task(z: dict[str, np.ndarray], e: int, centre: np.ndarray, length: float) -> tuple[np.ndarray, np.ndarray]:
    """(rows, target) of example ``e``'s task on the scaled wrench."""
    m = int(z["num_contacts"][e])
    c, f = z["contacts"][e, :m], z["forces"][e, :m]
    w = np.einsum("mij,mj->i", grasp_maps(c, centre, length), f)
    if not bool(z["articulated"][e]):
        return np.eye(6), w
    task = articulated_task(str(z["joint_type"][e]), z["joint_axis"][e], z["joint_origin"][e], centre, length)
    return task.projection, task.projection @ w


def shard_grasp_sets(z: dict[str, np.ndarray]) -> GraspSets:
    """The :class:`GraspSets` of every example of one shard (its arrays as written by `research.data.generate`)."""
    n_ex = int(z["num_examples"])
    c_max = z["contacts"].shape[1] if n_ex else 1
    size = int(z["max_set"]) if "max_set" in z else MAX_SET
    out = GraspSets(
        np.full((n_ex, size, c_max, 3), np.nan), np.full((n_ex, size, c_max, 3), np.nan),
        np.full((n_ex, size, c_max, 3), np.nan), np.ones(n_ex, dtype=np.int64),
    )  # fmt: skip
    if n_ex == 0:
        return out
    groups: dict[tuple[int, str], list[int]] = {}
    for e in range(n_ex):
        groups.setdefault((int(z["obj_index"][e]), str(z["hand"][e])), []).append(e)
    for (oi, _hand), members in groups.items():
        centre, length = z["object_centre"][oi], float(z["object_length"][oi])
        keys = {np.round(z["contacts"][e], 9).tobytes(): e for e in members}  # one example per distinct grasp
        grasps = list(keys.values())
        for e in members:
            m_e = int(z["num_contacts"][e])
            out.contacts[e, 0, :m_e] = z["contacts"][e, :m_e]
            out.normals[e, 0, :m_e] = z["contact_normals"][e, :m_e]
            out.forces[e, 0, :m_e] = z["forces"][e, :m_e]
            rows, target = _task(z, e, centre, length)
            own = np.round(z["contacts"][e], 9).tobytes()
            k = 1
            for gi in grasps:
                if k == size:
                    break
                if np.round(z["contacts"][gi], 9).tobytes() == own:
                    continue
                m = int(z["num_contacts"][gi])
                c, n = z["contacts"][gi, :m], z["contact_normals"][gi, :m]
                f = feasible_forces(c, n, float(z["friction"][e]), rows, target, centre, length)
                if f is None:
                    continue
                out.contacts[e, k, :m], out.normals[e, k, :m], out.forces[e, k, :m] = c, n, f
                k += 1
            out.count[e] = k
    return out


def grasps_in_mask(points: np.ndarray, mask: np.ndarray, set_contacts: np.ndarray, count: int) -> np.ndarray:
    """(G,) bool: which of an example's valid grasps have every contact on the region mask (its nearest point
    allowed). A partial mask is drawn around the example's own grasp (row 0, always inside), so the others may
    lie outside it: a target there would contradict the mask the network is given.

    Args:
        points: (N, 3) the object's points. mask: (N,) bool. set_contacts: (G, C, 3), NaN rows padding.
        count: how many of the G rows are grasps.
    """
    inside = np.zeros(len(set_contacts), dtype=bool)
    for g in range(count):
        c = set_contacts[g][np.isfinite(set_contacts[g][:, 0])]
        nearest = np.argmin(np.linalg.norm(points[None, :, :] - c[:, None, :], axis=2), axis=1)
        inside[g] = bool(np.all(mask[nearest]))
    inside[0] = True
    return inside


def set_maps(points: np.ndarray, normals: np.ndarray, contacts: GraspRows,
             contact_normals: GraspRows, forces: GraspRows,
             scale: float) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """Heatmaps (G, N) and force maps (G, N, 3) of G grasps (`research.data.labels.heat_and_force` each).

    Args:
        points, normals: (N, 3) the object's oriented points. scale: its longest side (the kernel's s).
        contacts, contact_normals, forces: (G, C, 3) the grasps, NaN rows padding (or G arrays (C_g, 3)).
    """
    heats, maps = [], []
    for c, n, f in zip(contacts, contact_normals, forces, strict=True):
        ok = np.isfinite(c[:, 0])
        heat, force = heat_and_force(points, normals, c[ok], n[ok], f[ok], scale)
        heats.append(heat)
        maps.append(force)
    return np.stack(heats), np.stack(maps)


def set_region(points: np.ndarray, normals: np.ndarray, contacts: GraspRows,
               contact_normals: GraspRows, forces: GraspRows) -> np.ndarray:  # fmt: skip
    """(N,) bool: the valid region of G grasps (as `set_maps` takes them) on the object's points (N, 3) — where
    any grasp's heat is at least ``REGION_HEAT``, the kernel scaled by the points' longest side as the labels'."""
    heats, _ = set_maps(points, normals, contacts, contact_normals, forces, float(np.ptp(points, axis=0).max()))
    return np.asarray((heats >= REGION_HEAT).any(axis=0))
