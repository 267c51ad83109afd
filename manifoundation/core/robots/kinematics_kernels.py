"""Forward kinematics and point Jacobians of one pose as compiled loops (`manifoundation.core.robots.kinematics`' fast
path).

The refinement asks `KinematicTree.body_poses` and `point_jacobian` for a batch of one pose ≈ 40 times a request.
In torch each is ≈ 25 tensor operations on 3 × 3 blocks, whose per-call overhead (≈ 5-10 µs each) is nearly all
of their cost; the same formulas as loops over the bodies take a few µs. They are the torch code's formulas term
for term (`tests/core/robots/test_kinematics_kernels.py` checks them against it); batches, gradients and other
devices keep the torch code.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit


@njit(cache=True)
def body_poses_one(
    palm_pos: np.ndarray, palm_quat: np.ndarray, q: np.ndarray, src: np.ndarray, mult: np.ndarray,
    offset: np.ndarray, rev: np.ndarray, pris: np.ndarray, axis: np.ndarray, origin: np.ndarray,
    parent: np.ndarray,
) -> np.ndarray:  # fmt: skip
    """World poses (nb, 4, 4) of every body for one pose.

    Args:
        palm_pos: (3,). palm_quat: (4,) wxyz, normalised here. q: (D,) the free joints (D may be 0).
        src, mult, offset: (nb,) each body's joint angle θ_b = q[src_b] · mult_b + offset_b (offset alone
            without joints). rev, pris: (nb,) 1.0 for a revolute / prismatic joint. axis: (nb, 3) joint axes.
        origin: (nb, 4, 4) each body's joint frame in its parent body. parent: (nb,) parent index (parents
            first; body 0 is the palm).
    """
    nb = origin.shape[0]
    T = np.zeros((nb, 4, 4))
    norm = math.sqrt(palm_quat[0] ** 2 + palm_quat[1] ** 2 + palm_quat[2] ** 2 + palm_quat[3] ** 2)
    w, x, y, z = palm_quat[0] / norm, palm_quat[1] / norm, palm_quat[2] / norm, palm_quat[3] / norm
    T[0, 0, 0], T[0, 0, 1], T[0, 0, 2] = 1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)
    T[0, 1, 0], T[0, 1, 1], T[0, 1, 2] = 2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)
    T[0, 2, 0], T[0, 2, 1], T[0, 2, 2] = 2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)
    T[0, 0, 3], T[0, 1, 3], T[0, 2, 3], T[0, 3, 3] = palm_pos[0], palm_pos[1], palm_pos[2], 1.0
    R = np.empty((3, 3))
    local = np.zeros((4, 4))
    local[3, 3] = 1.0
    for b in range(1, nb):
        theta = q[src[b]] * mult[b] + offset[b] if q.shape[0] else offset[b]
        s = math.sin(theta) * rev[b]
        cm = (1 - math.cos(theta)) * rev[b]
        a0, a1, a2 = axis[b, 0], axis[b, 1], axis[b, 2]
        # R = I + s K + cm K², K = [a]×
        K = ((0.0, -a2, a1), (a2, 0.0, -a0), (-a1, a0, 0.0))
        for r in range(3):
            for c in range(3):
                k2 = K[r][0] * K[0][c] + K[r][1] * K[1][c] + K[r][2] * K[2][c]
                R[r, c] = (1.0 if r == c else 0.0) + s * K[r][c] + cm * k2
        tp = theta * pris[b]
        t0, t1, t2 = tp * a0, tp * a1, tp * a2
        for r in range(3):
            for c in range(3):
                local[r, c] = origin[b, r, 0] * R[0, c] + origin[b, r, 1] * R[1, c] + origin[b, r, 2] * R[2, c]
            local[r, 3] = origin[b, r, 3] + (origin[b, r, 0] * t0 + origin[b, r, 1] * t1 + origin[b, r, 2] * t2)
        p = parent[b]
        for r in range(3):
            for c in range(4):
                T[b, r, c] = T[p, r, 0] * local[0, c] + T[p, r, 1] * local[1, c] + T[p, r, 2] * local[2, c] + (
                    T[p, r, 3] * local[3, c])  # fmt: skip
        T[b, 3, 3] = 1.0
    return T


@njit(cache=True)
def point_jacobian_one(
    T: np.ndarray, bodies: np.ndarray, points: np.ndarray, palm_pos: np.ndarray, axis: np.ndarray,
    rev: np.ndarray, pris: np.ndarray, weights: np.ndarray,
) -> np.ndarray:  # fmt: skip
    """Jacobian (n, 3, 6 + D) of world points (n, 3) rigidly attached to ``bodies`` (n,), at body poses T (nb, 4,
    4): columns 0:3 palm translation, 3:6 a world rotation about the palm, then the joints; ``weights`` (nb, nb,
    D) the coupling-weighted ancestor table (`KinematicTree`'s ``body_weights``)."""
    n = points.shape[0]
    nb, D = weights.shape[0], weights.shape[2]
    J = np.zeros((n, 3, 6 + D))
    for i in range(n):
        r0, r1, r2 = points[i, 0] - palm_pos[0], points[i, 1] - palm_pos[1], points[i, 2] - palm_pos[2]
        J[i, 0, 0] = J[i, 1, 1] = J[i, 2, 2] = 1.0
        J[i, 0, 4], J[i, 0, 5] = r2, -r1
        J[i, 1, 3], J[i, 1, 5] = -r2, r0
        J[i, 2, 3], J[i, 2, 4] = r1, -r0
    if D == 0:
        return J
    # per body k: its world axis a_k (revolute part) and a_k × o_k · rev − a_k · pris
    lever = np.empty((nb, 3))
    turn = np.empty((nb, 3))
    for k in range(nb):
        w0 = T[k, 0, 0] * axis[k, 0] + T[k, 0, 1] * axis[k, 1] + T[k, 0, 2] * axis[k, 2]
        w1 = T[k, 1, 0] * axis[k, 0] + T[k, 1, 1] * axis[k, 1] + T[k, 1, 2] * axis[k, 2]
        w2 = T[k, 2, 0] * axis[k, 0] + T[k, 2, 1] * axis[k, 1] + T[k, 2, 2] * axis[k, 2]
        o0, o1, o2 = T[k, 0, 3], T[k, 1, 3], T[k, 2, 3]
        turn[k, 0], turn[k, 1], turn[k, 2] = w0 * rev[k], w1 * rev[k], w2 * rev[k]
        lever[k, 0] = (w1 * o2 - w2 * o1) * rev[k] - w0 * pris[k]
        lever[k, 1] = (w2 * o0 - w0 * o2) * rev[k] - w1 * pris[k]
        lever[k, 2] = (w0 * o1 - w1 * o0) * rev[k] - w2 * pris[k]
    # per body j and joint d: A = Σ_k W[j,k,d] turn_k, C = Σ_k W[j,k,d] lever_k; a point p on j: A × p − C
    A = np.zeros((nb, D, 3))
    C = np.zeros((nb, D, 3))
    for j in range(nb):
        for k in range(nb):
            for d in range(D):
                wt = weights[j, k, d]
                if wt != 0.0:
                    for c in range(3):
                        A[j, d, c] += wt * turn[k, c]
                        C[j, d, c] += wt * lever[k, c]
    for i in range(n):
        j = bodies[i]
        p0, p1, p2 = points[i, 0], points[i, 1], points[i, 2]
        for d in range(D):
            a0, a1, a2 = A[j, d, 0], A[j, d, 1], A[j, d, 2]
            J[i, 0, 6 + d] = (a1 * p2 - a2 * p1) - C[j, d, 0]
            J[i, 1, 6 + d] = (a2 * p0 - a0 * p2) - C[j, d, 1]
            J[i, 2, 6 + d] = (a0 * p1 - a1 * p0) - C[j, d, 2]
    return J


@njit(cache=True)
def apply_delta_one(
    palm_pos: np.ndarray, palm_quat: np.ndarray, q: np.ndarray, delta: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """`Hand.apply_delta` for one pose: the palm moved by δ[0:3], turned by exp(δ[3:6]) (world frame, wxyz
    quaternions), the joints by δ[6:]; (3,), (4,), (D,)."""
    w0, w1, w2 = delta[3], delta[4], delta[5]
    angle = math.sqrt(w0 * w0 + w1 * w1 + w2 * w2)
    half = 0.5 * angle
    k = 0.5 - angle * angle / 48.0 if angle < 1e-8 else math.sin(half) / angle
    aw, ax, ay, az = math.cos(half), w0 * k, w1 * k, w2 * k
    bw, bx, by, bz = palm_quat[0], palm_quat[1], palm_quat[2], palm_quat[3]
    quat = np.array([
        aw * bw - ax * bx - ay * by - az * bz,
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
    ])  # fmt: skip
    quat /= math.sqrt(quat[0] ** 2 + quat[1] ** 2 + quat[2] ** 2 + quat[3] ** 2)
    return palm_pos + delta[:3], quat, q + delta[6:]


@njit(cache=True)
def on_bodies_one(T: np.ndarray, bodies: np.ndarray, local: np.ndarray, translate: bool) -> np.ndarray:
    """Body-frame points or directions (K, 3) on ``bodies`` (K,) in the world at body poses T (nb, 4, 4): R p + t
    (``translate``) or R p."""
    out = np.empty((local.shape[0], 3))
    for k in range(local.shape[0]):
        b = bodies[k]
        p0, p1, p2 = local[k, 0], local[k, 1], local[k, 2]
        for r in range(3):
            v = T[b, r, 0] * p0 + T[b, r, 1] * p1 + T[b, r, 2] * p2
            out[k, r] = v + T[b, r, 3] if translate else v
    return out
