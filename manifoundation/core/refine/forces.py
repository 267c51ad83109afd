"""The contact-force problem (paper Eq. 6-8): ``min ‖R Σ G_i f_i − τ‖²`` with f_i in exact friction cones.

Written with auxiliary variables ``t = R G f − τ`` and the epigraph ``min s, ‖t‖ ≤ s`` (same minimiser as
‖t‖²): a ``P = 2 GᵀG`` formulation is singular whenever G is rank-deficient and made Clarabel fail on ~1 % of
random instances; this one is always well posed, and the solver's tolerance applies to ‖r‖ itself rather than to
‖r‖², so residuals of 1e-8 are resolved (with ‖r‖² the interior point stops near ‖r‖ ≈ 1e-4). Normal forces
are bounded, ``f_i·(−n_i) ≤ max_normal_force`` (default 1, paper §III-B: unit target wrench and forces of at most
one in the normal direction). Force closure adds
``Σ_i f_i·(−n_i) = 1``, which excludes f = 0, and — since Gf = 0 alone is also met by grasps on the boundary of
force closure (two opposing fingers and idle others: Ferrari–Canny ε = 0) — asks every finger to carry a share
``f_i·(−n_i) ≥ CLOSURE_MIN_SHARE / m`` inside a cone narrowed to ``CLOSURE_CONE_SHRINK · μ`` (a design friction
well below the object's, see the constant). Forces strictly inside the cones with Gf = 0 and a full-rank G is the
classical force-closure condition. `solve_forces_cvxpy` is the plain CVXPY reference.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from manifoundation.core.refine.conic import ConicProblem
from manifoundation.core.refine.grasp import cone_rows, grasp_maps
from manifoundation.core.refine.wrench import WrenchTask

DEFAULT_MAX_NORMAL_FORCE = 1.0
CLOSURE_MIN_SHARE = 0.25
CLOSURE_CONE_SHRINK = 0.3
"""Force closure with three or more contacts is designed for 0.3 μ (0.15 at the default μ 0.5), as BODex designs
for 0.1 what the benchmark tests at 0.6: a position-controlled squeeze presses each finger along its normal with
whatever stiffness the finger has there, so the pushes balance only where the normals nearly oppose, which a narrow
cone demands. First answers on 43 third-party objects that held in the simulated grasp test (exact mesh, `mani-lab
eval physics`) with 0.9 → 0.3: LEAP 4 → 12, LEAP Hand 7 → 13, Allegro 11 → 14, Shadow 3 → 17, Barrett 14 → 18, Kinova
17 → 21; 0.5 and 0.2 held fewer over the four dexterous hands (research/results/physics.md). Verification solves the
same cones, so fewer answers are verified (LEAP 41 → 29 of 43) and refinement takes longer (p50 LEAP 0.55 → 1.1 s)."""
TWO_CONTACT_CONE_SHRINK = 0.9
"""Two contacts (a parallel gripper's pads) keep 0.9 μ: two flat pads on parallel faces touch in patches, and the
offset between the points the contact model picks on them is an artefact a narrow cone makes refinement chase (a
box's given antipodal contacts stalled unverified at 0.3 μ; the Panda gripper held 11 → 19 of 43 with 0.3 but
verified 34 → 31)."""


CONE_MARGIN = 1e-4


def cone_mu(task: WrenchTask, mu: float | np.ndarray, contacts: int) -> float | np.ndarray:
    """Friction coefficient of the optimisation's cones for ``contacts`` contacts: narrowed for force closure
    (``CLOSURE_CONE_SHRINK``, two contacts ``TWO_CONTACT_CONE_SHRINK``); otherwise by ``CONE_MARGIN``, so a force on
    the cone's edge is inside it for a check with its own rounding (0.8000001 > μ failed one)."""
    if not task.closure:
        return mu * (1.0 - CONE_MARGIN)
    return mu * (TWO_CONTACT_CONE_SHRINK if contacts <= 2 else CLOSURE_CONE_SHRINK)


def min_normal_force(task: WrenchTask, m: int) -> float:
    """Lower bound on each normal force (closure only)."""
    return CLOSURE_MIN_SHARE / m if task.closure else 0.0


@dataclass(frozen=True)
class ForceSolution:
    """Optimal contact forces at fixed contacts.

    Attributes:
        forces: (m, 3) world-frame forces applied by the fingertips on the object.
        residual: (k,) ``R Σ G_i f_i − τ`` at the optimum.
        residual_norm: ‖residual‖ (inf when the solver failed).
        status: Clarabel's status name.
    """

    forces: np.ndarray
    residual: np.ndarray
    residual_norm: float
    status: str


def wrench_matrix(task: WrenchTask, points: np.ndarray) -> np.ndarray:
    """(k, 3m) map from stacked forces to the projected scaled wrench, ``R [G_1 … G_m]``."""
    g = grasp_maps(points, task.centre, task.length)  # (m, 6, 3)
    gmat: np.ndarray = task.projection @ np.concatenate(list(g), axis=1)
    return gmat


def solve_forces(
    task: WrenchTask,
    points: np.ndarray,
    normals: np.ndarray,
    mu: float | np.ndarray,
    max_normal_force: float = DEFAULT_MAX_NORMAL_FORCE,
) -> ForceSolution:
    """Solve Eq. (6-8) with Clarabel's native API.

    Args:
        task: residual definition (rigid, articulated or closure).
        points: (m, 3) contact points (fingertip positions; need not be on the surface).
        normals: (m, 3) outward unit normals at their projections on the surface.
        mu: friction coefficient.
        max_normal_force: bound on each normal component.

    Returns:
        The solution; a failed solve gives zero forces, residual ``−τ`` and ``residual_norm = inf``.
    """
    m, k = len(points), task.rows
    gmat = wrench_matrix(task, points)
    n = 3 * m + k + 1  # x = [f, t, s]
    prob = ConicProblem(n)
    prob.q[-1] = 1.0
    prob.zero(np.hstack([-gmat, np.eye(k), np.zeros((k, 1))]), -task.target)
    epi = np.zeros((k + 1, n))
    epi[0, -1], epi[1:, 3 * m : 3 * m + k] = -1.0, -np.eye(k)
    prob.soc(epi, np.zeros(k + 1))
    nrows = np.zeros((m, n))
    for i in range(m):
        nrows[i, 3 * i : 3 * i + 3] = -normals[i]
    if task.closure:
        prob.zero(nrows.sum(axis=0, keepdims=True), np.ones(1))
        prob.leq(-nrows, np.full(m, -min_normal_force(task, m)))
    prob.leq(nrows, np.full(m, max_normal_force))
    cones = cone_rows(normals, cone_mu(task, mu, m))
    for i in range(m):
        a = np.zeros((3, n))
        a[:, 3 * i : 3 * i + 3] = -cones[i]
        prob.soc(a, np.zeros(3))
    x, status = prob.solve()
    if x is None:
        return ForceSolution(np.zeros((m, 3)), -task.target.copy(), float("inf"), status)
    forces = project_to_cones(x[: 3 * m].reshape(m, 3), normals, cone_mu(task, mu, m))
    residual = gmat @ forces.reshape(-1) - task.target
    return ForceSolution(forces, residual, float(np.linalg.norm(residual)), status)


def project_to_cones(forces: np.ndarray, normals: np.ndarray, mu: float | np.ndarray) -> np.ndarray:
    """Each force (m, 3) projected onto its friction cone (outward normals (m, 3)): the interior-point solver
    meets the cones to its tolerance only, and a force 2e-4 outside (ratio 0.80014 for μ = 0.8) failed an
    outside check. Forces inside are unchanged."""
    n = normals / np.linalg.norm(normals, axis=1, keepdims=True)
    mu_c = np.broadcast_to(np.asarray(mu, dtype=np.float64), (len(forces),))
    push = -np.einsum("ij,ij->i", forces, n)
    tangential = forces + push[:, None] * n
    t_norm = np.linalg.norm(tangential, axis=1)
    s = mu_c * push  # the cone is ‖tangential‖ ≤ s
    out = forces.copy()
    outside = t_norm > s
    for i in np.flatnonzero(outside):
        if t_norm[i] <= -s[i]:
            out[i] = 0.0
            continue
        a = 0.5 * (s[i] + t_norm[i])  # projection of (s, v) onto {‖v‖ ≤ s}: (a, a v/‖v‖)
        out[i] = -(a / mu_c[i]) * n[i] + a * tangential[i] / t_norm[i]
    return out


def solve_forces_cvxpy(
    task: WrenchTask,
    points: np.ndarray,
    normals: np.ndarray,
    mu: float | np.ndarray,
    max_normal_force: float = DEFAULT_MAX_NORMAL_FORCE,
) -> ForceSolution:
    """The same problem written plainly in CVXPY (reference for tests; ~10× slower)."""
    import cvxpy as cp

    # cp.sum, cp.hstack and cp.sum_squares reach `cvxpy` by a star import of `cvxpy.atoms`, which exports
    # nothing explicitly (mypy --strict sees no such attributes): the same functions, from where they are defined
    from cvxpy.atoms.affine.hstack import hstack
    from cvxpy.atoms.affine.sum import sum as cp_sum
    from cvxpy.atoms.sum_squares import sum_squares

    m = len(points)
    gmat = wrench_matrix(task, points)
    f = cp.Variable(3 * m)
    cones = cone_rows(normals, cone_mu(task, mu, m))
    cons: list[Any] = []
    normal_force = []
    for i in range(m):
        fi = f[3 * i : 3 * i + 3]
        cons.append(cp.SOC(cones[i][0] @ fi, cones[i][1:] @ fi))
        normal_force.append(-normals[i] @ fi)
        cons.append(-normals[i] @ fi <= max_normal_force)
        cons.append(-normals[i] @ fi >= min_normal_force(task, m))
    if task.closure:
        cons.append(cp_sum(hstack(normal_force)) == 1)
    prob = cp.Problem(cp.Minimize(sum_squares(gmat @ f - task.target)), cons)
    prob.solve(solver=cp.CLARABEL)
    if f.value is None:
        return ForceSolution(np.zeros((m, 3)), -task.target.copy(), float("inf"), str(prob.status))
    residual = gmat @ f.value - task.target
    return ForceSolution(f.value.reshape(m, 3), residual, float(np.linalg.norm(residual)), str(prob.status))
