"""One SCP step (paper Eq. 9-16) over (δq, f = f* + δf), with Clarabel's native API or plain CVXPY.

    min  ‖r* + B δq + R G δf‖² + λ Σ_i (Φ_i + ∇Φ_iᵀ J_i δq)² + ρ Σ slacks + ε Σ (δq_j / s_j)²
    s.t. f_i ∈ FC(μ) (exact SOC), f_i·(−n_i) ≤ f_max, [closure: Σ f_i·(−n_i) = 1, shares and narrowed cones
         as in `manifoundation.core.refine.forces`]
         q_min ≤ q + δq ≤ q_max,  |δq| ≤ s_q,  |δf| ≤ s_f
         Φ(c_k) − r_k + ∇Φ(c_k)ᵀ J_k δq + σ_k ≥ 0              (active guards: surface samples r = 0, spheres)
         ‖c_i − c_j‖ + u_ijᵀ (J_i − J_j) δq + σ_ij ≥ ε_i + ε_j   (active pairs, linearised Eq. 15)

B = R Σ_i ([0; −[f_i*]× J_i / ρ] + G_i (−[f_i*]× [n_i]× ∂n_i/∂p J_i)) is ∂(R G(p) f*)/∂q: the contact moves
(lever arm) and, on a curved surface, its friction cone turns with the normal and carries f* along. The
non-penetration and self-collision rows carry slacks σ ≥ 0 with an exact-penalty weight ρ, so a step always
exists even from a penetrating start. The native build uses
auxiliary variables for the residual and the tip distances (``P`` diagonal), as the force problem does.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from manifoundation.core.refine.conic import ConicProblem, Rows
from manifoundation.core.refine.forces import cone_mu, min_normal_force, wrench_matrix
from manifoundation.core.refine.grasp import cone_rows, grasp_maps, skew
from manifoundation.core.refine.state import Linearisation


@dataclass(frozen=True)
class StepParams:
    """Trust region and weights of one step.

    Attributes:
        trust: (n,) bound on |δq| per column (palm translation m, palm rotation rad, joints rad).
        trust_force: bound on each |δf| component.
        tip_weight: λ on the squared tip distances (1/m²).
        penalty: ρ on the slacks (per metre of violation).
        active_margin: guards farther than this from the object are left out (m).
        pair_margin: self-collision pairs with a larger gap are left out (m).
        regularisation: ε on (δq_j / s_j)².
        residual_weight: the wrench residual's weight (1; less while the fingers close, `RefineConfig`).
    """

    trust: np.ndarray
    trust_force: float
    tip_weight: float = 100.0
    penalty: float = 10.0
    active_margin: float = 0.02
    pair_margin: float = 0.01
    regularisation: float = 1e-6
    residual_weight: float = 1.0


@dataclass(frozen=True)
class StepSolution:
    """δq (n,), the new forces (m, 3), the model's objective value, and the solver status."""

    delta: np.ndarray | None
    forces: np.ndarray | None
    objective: float
    status: str


def _can_bind(rows: np.ndarray, rhs: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """(r,) bool: whether the guard ``rhs + row·δq ≥ 0`` (rows (r, n)) can be violated for some δq in the box
    [lo, hi] (n,). A row that cannot is redundant (its slack is 0 at every feasible step): leaving it and its
    slack out leaves the step unchanged, and at a small trust region most rows are such."""
    reach = np.minimum(rows * lo[None], rows * hi[None]).sum(axis=1)  # the least row·δq within the box
    return np.asarray(rhs + reach < 0.0)


def _model_terms(lin: Linearisation, params: StepParams) -> dict[str, np.ndarray]:
    """Matrices shared by both builds."""
    task = lin.task
    gmat = wrench_matrix(task, lin.tips)  # (k, 3m)
    # ∂(R G f*)/∂q: torque part of G_i f* changes by δp × f* = −[f*]× J δq, over ρ
    dtorque = np.einsum("mab,mbn->an", -skew(lin.forces), lin.tip_jac) / task.length
    bmat = task.projection @ np.vstack([np.zeros((3, dtorque.shape[1])), dtorque])
    # sliding turns the contact frame by ω = n × (∂n/∂p) J δq, which turns f* by ω × f* = −[f*]× ω
    turn = -skew(lin.forces) @ skew(lin.normals) @ lin.normal_jac  # (m, 3, 3)
    dforce = np.einsum("mab,mbn->man", turn, lin.tip_jac)
    g = grasp_maps(lin.tips, task.centre, task.length)
    bmat = bmat + task.projection @ np.einsum("mia,man->in", g, dforce)
    tip_rows = np.einsum("ma,man->mn", lin.tip_grad, lin.gap_jac)
    lo = np.maximum(-params.trust, np.concatenate([np.full(6, -np.inf), lin.lower - lin.q]))
    hi = np.minimum(params.trust, np.concatenate([np.full(6, np.inf), lin.upper - lin.q]))
    lo = np.minimum(lo, 0.0)  # a start outside the limits may only move back towards them
    hi = np.maximum(hi, 0.0)
    active = np.flatnonzero(lin.clear < params.active_margin)
    sph_rows = np.einsum("sa,san->sn", lin.clear_grad[active], lin.clear_jac[active])
    keep = _can_bind(sph_rows, lin.clear[active], lo, hi)
    sph_rows, sph_rhs = sph_rows[keep], lin.clear[active][keep]  # row·δq + σ ≥ −rhs
    if len(lin.pair_idx):
        gap = lin.pair_dist - lin.sph_radius[lin.pair_idx].sum(axis=1)
        pairs = np.flatnonzero(gap < params.pair_margin)
        i, j = lin.pair_idx[pairs, 0], lin.pair_idx[pairs, 1]
        pair_rows = np.einsum("pa,pan->pn", lin.pair_dir[pairs], lin.sph_jac[i] - lin.sph_jac[j])
        keep = _can_bind(pair_rows, gap[pairs], lo, hi)
        pair_rows, pair_rhs = pair_rows[keep], gap[pairs][keep]
    else:
        pair_rows, pair_rhs = np.zeros((0, lin.tip_jac.shape[2])), np.zeros(0)
    return {
        "G": gmat,
        "B": bmat,
        "r0": lin.solution.residual - gmat @ lin.forces.reshape(-1),  # r* − R G f* = −τ (constant part)
        "tip_rows": tip_rows,
        "sph_rows": sph_rows,
        "sph_rhs": sph_rhs,
        "pair_rows": pair_rows,
        "pair_rhs": pair_rhs,
        "lo": lo,
        "hi": hi,
    }


def solve_step(lin: Linearisation, params: StepParams) -> StepSolution:
    """The step with Clarabel's native API (the fast path, ~1-2 ms)."""
    t = _model_terms(lin, params)
    m, k = len(lin.tips), lin.task.rows
    n = lin.tip_jac.shape[2]
    a, b = len(t["sph_rhs"]), len(t["pair_rhs"])
    iq, iff, ir, ip = 0, n, n + 3 * m, n + 3 * m + k  # offsets: δq, f, t_r, t_φ
    isl = ip + m
    nx = isl + a + b
    prob = ConicProblem(nx)
    prob.p_diag[iq:iff] = 2 * params.regularisation / np.maximum(params.trust, 1e-9) ** 2
    prob.p_diag[ir:ip] = 2.0 * params.residual_weight
    prob.p_diag[ip:isl] = 2.0 * params.tip_weight
    prob.q[isl:] = params.penalty
    # t_r = r0 + B δq + G f
    prob.zero(Rows.beside(Rows.dense(-t["B"], iq), Rows.dense(-t["G"], iff), Rows.eye(k, ir)), t["r0"])
    # t_φ = Φ + ∇Φᵀ J δq
    prob.zero(Rows.beside(Rows.dense(-t["tip_rows"], iq), Rows.eye(m, ip)), lin.tip_phi)
    # row i: −n_i · f_i (the normal force of contact i)
    nrow = Rows(m, np.repeat(np.arange(m), 3), iff + np.arange(3 * m), -lin.normals.reshape(-1))
    if lin.task.closure:
        prob.zero(Rows(1, np.zeros(3 * m, dtype=np.int64), nrow.col, nrow.val), np.ones(1))
        prob.leq(Rows(m, nrow.row, nrow.col, -nrow.val), np.full(m, -min_normal_force(lin.task, m)))
    prob.leq(nrow, np.full(m, lin.max_normal_force))
    # box: lo ≤ δq ≤ hi, |f − f*| ≤ s_f
    prob.leq(Rows.eye(n, iq), t["hi"])
    prob.leq(Rows.eye(n, iq, -1.0), -t["lo"])
    f0 = lin.forces.reshape(-1)
    prob.leq(Rows.eye(3 * m, iff), f0 + params.trust_force)
    prob.leq(Rows.eye(3 * m, iff, -1.0), -(f0 - params.trust_force))
    # spheres: −row δq − σ ≤ rhs ; pairs likewise ; σ ≥ 0
    if a:
        prob.leq(Rows.beside(Rows.dense(-t["sph_rows"], iq), Rows.eye(a, isl, -1.0)), t["sph_rhs"])
    if b:
        prob.leq(Rows.beside(Rows.dense(-t["pair_rows"], iq), Rows.eye(b, isl + a, -1.0)), t["pair_rhs"])
    if a + b:
        prob.leq(Rows.eye(a + b, isl, -1.0), np.zeros(a + b))
    cones = cone_rows(lin.normals, cone_mu(lin.task, lin.mu, m))
    for i in range(m):
        prob.soc(Rows.dense(-cones[i], iff + 3 * i), np.zeros(3))
    x, status = prob.solve()
    if x is None:
        return StepSolution(None, None, float("inf"), status)
    obj = float(0.5 * x @ (prob.p_diag * x) + prob.q @ x)
    return StepSolution(x[iq:iff], x[iff:ir].reshape(m, 3), obj, status)


def solve_step_cvxpy(lin: Linearisation, params: StepParams) -> StepSolution:
    """The same step written plainly in CVXPY and rebuilt every call (the reference; ~10× slower)."""
    import cvxpy as cp

    t = _model_terms(lin, params)
    m = len(lin.tips)
    n = lin.tip_jac.shape[2]
    dq = cp.Variable(n)
    f = cp.Variable(3 * m)
    sig_s = cp.Variable(len(t["sph_rhs"]), nonneg=True)
    sig_p = cp.Variable(len(t["pair_rhs"]), nonneg=True)
    residual = t["r0"] + t["B"] @ dq + t["G"] @ f
    tip = lin.tip_phi + t["tip_rows"] @ dq
    obj = (
        params.residual_weight * cp.sum_squares(residual)
        + params.tip_weight * cp.sum_squares(tip)
        + params.regularisation * cp.sum_squares(cp.multiply(1 / np.maximum(params.trust, 1e-9), dq))
        + params.penalty * (cp.sum(sig_s) + cp.sum(sig_p))
    )
    cones = cone_rows(lin.normals, cone_mu(lin.task, lin.mu, m))
    f0 = lin.forces.reshape(-1)
    cons = [dq >= t["lo"], dq <= t["hi"], cp.abs(f - f0) <= params.trust_force]
    normal = []
    for i in range(m):
        fi = f[3 * i : 3 * i + 3]
        cons.append(cp.SOC(cones[i][0] @ fi, cones[i][1:] @ fi))
        normal.append(-lin.normals[i] @ fi)
        cons.append(-lin.normals[i] @ fi <= lin.max_normal_force)
        cons.append(-lin.normals[i] @ fi >= min_normal_force(lin.task, m))
    if lin.task.closure:
        cons.append(cp.sum(cp.hstack(normal)) == 1)
    if len(t["sph_rhs"]):
        cons.append(t["sph_rows"] @ dq + sig_s >= -t["sph_rhs"])
    if len(t["pair_rhs"]):
        cons.append(t["pair_rows"] @ dq + sig_p >= -t["pair_rhs"])
    prob = cp.Problem(cp.Minimize(obj), cons)
    prob.solve(solver=cp.CLARABEL)
    if dq.value is None:
        return StepSolution(None, None, float("inf"), str(prob.status))
    return StepSolution(np.asarray(dq.value), np.asarray(f.value).reshape(m, 3), float(prob.value), str(prob.status))
