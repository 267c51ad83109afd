"""The executed target-motion test (issue 63): squeeze, then gravity on and the palm carried along the task's motion.

The hand and object models, the pregrasp and the squeeze are the force-closure test's (`trial`); then gravity is
switched on (the object's 0.1 kg; the hand's bodies are gravity-compensated) and the palm follows the
task's rigid motion — the translation plus the rotation about the object's centre of mass, interpolated linearly
(translation) and along the shortest arc (rotation) over ``motion_seconds`` — and is held ``motion_hold_seconds``.
Success when the object's centre of mass ends within ``target_translation`` and its orientation within
``target_rotation`` of the target pose (the start pose moved by the task).

The palm is free and welded to a moving mocap body (DexGraspBench's base), not a mocap body itself: MuJoCo gives a
mocap body no velocity, so fingers carried by a teleported palm slide under the object's friction (measured: a
squeezed box slips out in the first 0.2 s of a 5 cm lift); the weld (solref 2 × timestep, the palm 1 kg) tracks the
motion within 0.01 mm here, and the hand is gravity-compensated so only the object's weight loads the grasp.
"""

from __future__ import annotations

import time
from typing import TYPE_CHECKING

import mujoco
import numpy as np

from manifoundation.core.physics.object_model import ObjectShape
from manifoundation.core.physics.protocol import MotionTrial, PhysicsResult, Protocol
from manifoundation.core.physics.scene import Scene, build_scene
from manifoundation.core.physics.trial import FALLBACK_SOLVER, _angle, _drive, _reset, _touching, diverged_count, start

if TYPE_CHECKING:
    from manifoundation.core.robots.hand import Hand


def simulate_motion(
    hand: Hand, palm_position: np.ndarray, palm_quaternion: np.ndarray, joints: np.ndarray,
    contact_points: np.ndarray, contact_normals: np.ndarray, fingertips: list[str], shape: ObjectShape,
    translation: np.ndarray, rotation: np.ndarray | None = None, protocol: Protocol | None = None,
) -> PhysicsResult:  # fmt: skip
    """Judge one grasp on a ``delta_pose`` task (arguments as `simulate_grasp`'s, plus the task's motion).

    Args:
        translation: (3,) m, the object's centre's displacement; rotation: (4,) wxyz about its centre (default none).

    Returns:
        `PhysicsResult` with ``test == "motion"``, no ``trials`` and the figures in ``motion``; ``reason`` is
        "reached", "missed" (ended outside the tolerance), "dropped" (no hand body touches it at the end) or
        "penetration" (the pregrasp penetrates more than ``max_penetration``).
    """
    p = protocol or Protocol()
    t0 = time.perf_counter()
    sc = build_scene(hand, palm_position, palm_quaternion, shape, p, moving=True)
    q = np.asarray(joints, float)
    pre, squeeze, gaps, pen = start(sc, hand, q, contact_points, contact_normals, fingertips, p)
    if pen > p.max_penetration:
        return PhysicsResult(False, [], "penetration", pen, gaps, 0, pre, squeeze, time.perf_counter() - t0,
                             test="motion", object_pieces=shape.source)  # fmt: skip
    trial, touching = _carry(sc, pre, q, squeeze, np.asarray(translation, float), rotation, p)
    if trial.unstable:  # Newton diverged: the same physics once more with the fallback solver (see trial)
        sc = build_scene(hand, palm_position, palm_quaternion, shape, p, moving=True)
        sc.model.opt.solver = FALLBACK_SOLVER
        trial, touching = _carry(sc, pre, q, squeeze, np.asarray(translation, float), rotation, p)
    reason = "reached" if trial.reached else "unstable" if trial.unstable else "dropped" if trial.dropped else "missed"
    return PhysicsResult(trial.reached, [], reason, pen, gaps, touching, pre, squeeze, time.perf_counter() - t0,
                         test="motion", motion=trial, object_pieces=shape.source)  # fmt: skip


def _axis_angle(rotation: np.ndarray | None) -> tuple[np.ndarray, float]:
    if rotation is None:
        return np.array([0.0, 0.0, 1.0]), 0.0
    r = np.asarray(rotation, float) / max(float(np.linalg.norm(rotation)), 1e-12)
    r = -r if r[0] < 0 else r
    s = float(np.linalg.norm(r[1:]))
    if s < 1e-12:
        return np.array([0.0, 0.0, 1.0]), 0.0
    return r[1:] / s, 2.0 * float(np.arctan2(s, r[0]))


def _quat(axis: np.ndarray, angle: float) -> np.ndarray:
    return np.concatenate([[np.cos(angle / 2)], np.sin(angle / 2) * axis])


def _mul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    out = np.zeros(4)
    mujoco.mju_mulQuat(out, a, b)
    return out


def _rotate(quat: np.ndarray, v: np.ndarray) -> np.ndarray:
    out = np.zeros(3)
    mujoco.mju_rotVecQuat(out, v, quat)
    return out


def _carry(
    sc: Scene, pre: np.ndarray, q: np.ndarray, squeeze: np.ndarray, translation: np.ndarray,
    rotation: np.ndarray | None, p: Protocol,
) -> tuple[MotionTrial, int]:  # fmt: skip
    m, d = sc.model, sc.data
    _reset(sc, pre)
    a = sc.object_qpos
    centre = d.xipos[sc.object_body].copy()
    quat0 = d.qpos[a + 3 : a + 7].copy()
    palm_pos, palm_quat = d.mocap_pos[0].copy(), d.mocap_quat[0].copy()
    _drive(sc, pre, q, p)
    _drive(sc, q, squeeze, p)
    touching = _touching(sc)
    m.opt.disableflags &= ~int(mujoco.mjtDisableBit.mjDSBL_GRAVITY)
    m.opt.gravity[:] = [0.0, 0.0, -p.gravity]
    axis, angle = _axis_angle(rotation)
    steps = max(1, round(p.motion_seconds / p.timestep))
    for i in range(steps):
        s = (i + 1) / steps
        r = _quat(axis, s * angle)
        d.mocap_pos[0] = centre + s * translation + _rotate(r, palm_pos - centre)
        d.mocap_quat[0] = _mul(r, palm_quat)
        mujoco.mj_step(m, d)
    mujoco.mj_step(m, d, nstep=max(1, round(p.motion_hold_seconds / p.timestep)))
    if diverged_count(sc) > 0:  # mjData was reset along the way: where the object ended says nothing
        return MotionTrial(float("inf"), 180.0, False, False, unstable=True), touching
    target_quat = _mul(_quat(axis, angle), quat0)
    err = float(np.linalg.norm(d.xipos[sc.object_body] - (centre + translation)))
    turned = _angle(target_quat, d.qpos[a + 3 : a + 7])
    dropped = _touching(sc) == 0
    ok = bool(np.isfinite(err) and err < p.target_translation and turned < p.target_rotation and not dropped)
    return MotionTrial(err if np.isfinite(err) else float("inf"), turned, dropped, ok), touching
