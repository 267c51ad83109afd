"""The test itself: pregrasp / squeeze targets, the start checks, and the six pushes (see `protocol`).

Why one module: the targets, the start checks and the pushes all work on one scene's MuJoCo state through the same
few steps (`_reset`, `_posed`, the squeezed state restored for each push); apart, they would hand that state
between modules.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import TYPE_CHECKING

import mujoco
import numpy as np

from manifoundation.core.physics.object_model import ObjectShape
from manifoundation.core.physics.protocol import DIRECTION_NAMES, DIRECTIONS, PhysicsResult, Protocol, Trial
from manifoundation.core.physics.scene import Scene, SceneCache, build_scene

if TYPE_CHECKING:
    from manifoundation.core.robots.hand import Hand

GAP_RANGE = 0.05
"""Fingertip gaps are measured up to this distance (m); farther tips report it."""


def simulate_grasp(
    hand: Hand, palm_position: np.ndarray, palm_quaternion: np.ndarray, joints: np.ndarray,
    contact_points: np.ndarray, contact_normals: np.ndarray, fingertips: list[str], shape: ObjectShape,
    protocol: Protocol | None = None, scenes: SceneCache | None = None,
) -> PhysicsResult:  # fmt: skip
    """Judge one grasp.

    Args:
        hand: the hand (its description is read, not its optimiser geometry).
        palm_position: (3,) and palm_quaternion: (4,) wxyz, world frame; joints: (D,) the grasp's free joints.
        contact_points, contact_normals: (m, 3) the answer's contacts and the object's outward normals there,
            one per fingertip link in ``fingertips``: the pregrasp moves each of them ``pregrasp_distance`` outward.
        shape: the object (`object_model`).
        protocol: settings (default: the benchmark's).
        scenes: compiled scenes of ``shape`` to re-pose instead of compiling one (`SceneCache`).
    """
    p = protocol or Protocol()
    t0 = time.perf_counter()
    if scenes is not None and scenes.shape is not shape:
        raise ValueError("scenes: a cache of another object's scenes")
    sc = (build_scene(hand, palm_position, palm_quaternion, shape, p) if scenes is None
          else scenes.scene(hand, palm_position, palm_quaternion, p))  # fmt: skip
    q = np.asarray(joints, float)
    pre, squeeze, gaps, pen = start(sc, hand, q, contact_points, contact_normals, fingertips, p)
    if pen > p.max_penetration:
        return PhysicsResult(False, [], "penetration", pen, gaps, 0, pre, squeeze, time.perf_counter() - t0,
                             object_pieces=shape.source)  # fmt: skip
    trials, touching, unstable = _pushes(sc, pre, q, squeeze, p)
    if unstable:  # Newton diverged: the same physics once more with the projected Gauss-Seidel solver
        sc.model.opt.solver = FALLBACK_SOLVER
        trials, touching, unstable = _pushes(sc, pre, q, squeeze, p)
    ok = len(trials) == len(DIRECTIONS) and all(t.held for t in trials)
    reason = "held" if ok else "unstable" if unstable else "moved"
    return PhysicsResult(ok, trials, reason, pen, gaps, touching, pre, squeeze, time.perf_counter() - t0,
                         object_pieces=shape.source)  # fmt: skip


BAD_ACCELERATION = mujoco.mjtWarning.mjWARN_BADQACC
FALLBACK_SOLVER = mujoco.mjtSolver.mjSOL_PGS
"""The constraint solver a diverged run is simulated again with. Newton (MuJoCo's default and the benchmark's)
diverges on some hands' frictional self-contacts under elliptic cones: two of Shadow's finger links touching (0.005
mm deep) sent its knuckle joints' accelerations to 3e6 rad/s² in one step, 32 of 43 Shadow answers on third-party
objects (measured with a 0.01 kg·m² joint armature). PGS solves the same constraints (same cones, friction, solref)
without diverging there; where Newton does not diverge the verdicts agree (LEAP 7/43, LEAP Hand 12/43, Allegro 9/43
held with either), and PGS costs about 1.5×, so it runs only after a divergence."""


def diverged_count(sc: Scene) -> int:
    """How often MuJoCo found a NaN / huge acceleration since the last reset. It then *resets* mjData to the model's
    initial state and carries on, which puts the object back where it started: a push of a diverged simulation
    pushes nothing, so a trial that diverged counts as failed ("unstable"), never as held."""
    return int(sc.data.warning[BAD_ACCELERATION].number)


def start(
    sc: Scene, hand: Hand, q: np.ndarray, contact_points: np.ndarray, contact_normals: np.ndarray,
    fingertips: list[str], p: Protocol,
) -> tuple[np.ndarray, np.ndarray, list[float], float]:  # fmt: skip
    """What every trial starts from: the pregrasp and squeeze targets (D,) (`moved_contacts`, ±``pregrasp_distance``
    within the joint limits), the fingertip gaps at the grasp (m,) and the penetration at the pregrasp (m)."""
    limits = (np.asarray(hand.lower, float), np.asarray(hand.upper, float))
    cps, cns = np.asarray(contact_points, float), np.asarray(contact_normals, float)
    pre = moved_contacts(sc, q, cps, cns, fingertips, p.pregrasp_distance, limits)
    squeeze = moved_contacts(sc, q, cps, cns, fingertips, -p.pregrasp_distance, limits)
    _reset(sc, q)
    gaps = tip_gaps(sc, fingertips)
    _reset(sc, pre)
    return pre, squeeze, gaps, _penetration(sc)


PREGRASP_DAMPING = 1e-4
"""λ of the pregrasp's damped least squares (m²/rad² per unit of joint motion): a contact whose normal a finger can
hardly move along (a thumb at a near-singular pose) moves as far as it can instead of sweeping sideways."""
PREGRASP_STEP = 0.1
"""Largest joint change (rad or m) of one pregrasp iteration: the Jacobian is re-evaluated along the way."""
PREGRASP_ITERATIONS = 30


def moved_contacts(
    sc: Scene, q: np.ndarray, points: np.ndarray, normals: np.ndarray, fingertips: list[str], distance: float,
    limits: tuple[np.ndarray, np.ndarray] | None = None,
) -> np.ndarray:
    """(D,) joints that move each contact point ``distance`` along its outward normal (negative: inward), within
    the joint limits: damped least squares on MuJoCo's point Jacobians, iterated on the forward kinematics (each
    contact is a point fixed to its fingertip body). The pregrasp is ``+p.pregrasp_distance``, the squeeze
    ``−p.pregrasp_distance``, both within the joint limits (what a robot's controller can be sent; a finger at a
    limit or at the edge of its reach moves its contact less). One linear step at the grasp, and the squeeze as
    its joint-space mirror (2 q − pre), moved a LEAP thumb's contact 2.4 cm along and 2.5 cm across its normal
    and swept it across the object."""
    bodies = [sc.model.body(sc.hand.link_body[link]).id for link in fingertips]
    if not bodies:
        return q.copy()
    _posed(sc, q)
    local = [sc.data.xmat[b].reshape(3, 3).T @ (x - sc.data.xpos[b]) for x, b in zip(points, bodies, strict=True)]
    unit = normals / np.maximum(np.linalg.norm(normals, axis=1, keepdims=True), 1e-12)
    target = points + distance * unit
    C = sc.coupling()
    jac = np.zeros((3, sc.model.nv))
    lo, hi = limits if limits is not None else (np.full(len(q), -np.inf), np.full(len(q), np.inf))
    cur = q.copy()
    for _ in range(PREGRASP_ITERATIONS):
        _posed(sc, cur)
        rows, err = [], []
        for lp, b, t in zip(local, bodies, target, strict=True):
            x = sc.data.xpos[b] + sc.data.xmat[b].reshape(3, 3) @ lp
            mujoco.mj_jac(sc.model, sc.data, jac, None, x, b)
            rows.append(jac @ C)
            err.append(t - x)
        J, e = np.vstack(rows), np.concatenate(err)
        if np.max(np.abs(e)) < 1e-7:
            break
        dq = _bounded_step(J, e, cur, lo, hi)
        if not np.any(dq):
            break
        dq *= min(1.0, PREGRASP_STEP / max(float(np.max(np.abs(dq))), 1e-12))
        cur = np.clip(cur + dq, lo, hi)
    return np.asarray(cur)


def _bounded_step(J: np.ndarray, e: np.ndarray, q: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """(D,) the damped least-squares step for J (3m, D) dq ≈ e (3m,) that leaves every joint at a limit the step
    would push past where it is: those joints are taken out and the step solved again with the others (an active
    set). Clipping the free solution instead moves the other joints of that finger as if the blocked one had moved
    too: a LEAP thumb at its lower limit then moved its contact 14 mm *outward* for a 10 mm inward squeeze."""
    free = np.ones(len(q), bool)
    dq = np.zeros(len(q))
    for _ in range(len(q)):
        Jf = J[:, free]
        dq = np.zeros(len(q))
        dq[free] = np.linalg.solve(Jf.T @ Jf + PREGRASP_DAMPING * np.eye(Jf.shape[1]), Jf.T @ e)
        blocked = free & (((q <= lo) & (dq < 0)) | ((q >= hi) & (dq > 0)))
        if not blocked.any():
            return dq
        free &= ~blocked
        if not free.any():
            return np.zeros(len(q))
    return dq


def tip_gaps(sc: Scene, fingertips: list[str]) -> list[float]:
    """Per fingertip link, the signed distance (m) from its body's geoms to the object's (at the current state)."""
    m, d = sc.model, sc.data
    obj = [g for g in range(m.ngeom) if m.geom_bodyid[g] == sc.object_body]
    out = []
    for link in fingertips:
        body = m.body(sc.hand.link_body[link]).id
        best = GAP_RANGE
        for g in (g for g in range(m.ngeom) if m.geom_bodyid[g] == body):
            for h in obj:
                best = min(best, float(mujoco.mj_geomDistance(m, d, g, h, GAP_RANGE, None)))
        out.append(best)
    return out


def _reset(sc: Scene, q: np.ndarray) -> None:
    """Fresh data at the hand's joints q (D,), its targets there, and everything ``mj_forward`` computes."""
    _at(sc, q)
    mujoco.mj_forward(sc.model, sc.data)


def _posed(sc: Scene, q: np.ndarray) -> None:
    """`_reset` without the collision detection and dynamics of ``mj_forward``: the body poses and what
    ``mj_jac`` reads (``mj_kinematics``, ``mj_comPos``), all the pregrasp's iterations need (a third of their
    time went to colliding the hand's convex pieces with the object)."""
    _at(sc, q)
    mujoco.mj_kinematics(sc.model, sc.data)
    mujoco.mj_comPos(sc.model, sc.data)


def _at(sc: Scene, q: np.ndarray) -> None:
    mujoco.mj_resetData(sc.model, sc.data)
    sc.set_joints(q)
    sc.data.ctrl[:] = q


def _penetration(sc: Scene) -> float:
    """Deepest hand-object or hand-hand penetration now (m, ≥ 0)."""
    m, d = sc.model, sc.data
    hand = set(sc.hand_bodies.tolist())
    deepest = 0.0
    for c in d.contact[: d.ncon]:
        b1, b2 = int(m.geom_bodyid[c.geom[0]]), int(m.geom_bodyid[c.geom[1]])
        involved = {b1, b2}
        if involved <= hand | {sc.object_body} and involved & hand:
            deepest = max(deepest, -float(c.dist))
    return deepest


def _touching(sc: Scene) -> int:
    m, d = sc.model, sc.data
    bodies = set()
    for c in d.contact[: d.ncon]:
        b1, b2 = int(m.geom_bodyid[c.geom[0]]), int(m.geom_bodyid[c.geom[1]])
        if sc.object_body in (b1, b2):
            bodies.add(b2 if b1 == sc.object_body else b1)
    return len(bodies)


def _drive(sc: Scene, a: np.ndarray, b: np.ndarray, p: Protocol) -> None:
    for j in range(p.interp_outer):
        sc.data.ctrl[:] = a + (b - a) * (j + 1) / p.interp_outer
        mujoco.mj_step(sc.model, sc.data, nstep=p.interp_inner)


@dataclass
class Squeezed:
    """The state every push starts from: the object's pose at the pregrasp (where displacement is measured from) and
    MuJoCo's whole integration state after pregrasp → grasp → squeeze. The approach is deterministic, so it is
    simulated once and restored for each push (bit-identical to simulating it six times, at a sixth of the cost)."""

    start_pos: np.ndarray  # (3,) the object's centre of mass at the pregrasp
    start_quat: np.ndarray  # (4,) wxyz
    state: np.ndarray  # mj_getState(mjSTATE_INTEGRATION)
    diverged: bool  # the approach itself diverged (`diverged_count`): every push fails


def _squeezed(sc: Scene, pre: np.ndarray, q: np.ndarray, squeeze: np.ndarray, p: Protocol) -> Squeezed:
    _reset(sc, pre)
    a = sc.object_qpos
    start_pos = sc.data.xipos[sc.object_body].copy()
    start_quat = sc.data.qpos[a + 3 : a + 7].copy()
    _drive(sc, pre, q, p)
    _drive(sc, q, squeeze, p)
    state = np.empty(mujoco.mj_stateSize(sc.model, INTEGRATION))
    mujoco.mj_getState(sc.model, sc.data, state, INTEGRATION)
    return Squeezed(start_pos, start_quat, state, diverged_count(sc) > 0)


INTEGRATION = mujoco.mjtState.mjSTATE_INTEGRATION


def _pushes(
    sc: Scene, pre: np.ndarray, q: np.ndarray, squeeze: np.ndarray, p: Protocol
) -> tuple[list[Trial], int, bool]:
    """The approach, then the six pushes from its end: (trials, hand bodies touching after the squeeze, whether the
    simulation diverged)."""
    squeezed = _squeezed(sc, pre, q, squeeze, p)
    touching = _touching(sc)
    trials: list[Trial] = []
    unstable = False
    for d, name in zip(DIRECTIONS, DIRECTION_NAMES, strict=True):
        trial, diverged = _push(sc, squeezed, d, name, p)
        trials.append(trial)
        unstable |= diverged
        if not trial.held and p.stop_at_first_failure:
            break
    return trials, touching, unstable


def _push(sc: Scene, squeezed: Squeezed, direction: np.ndarray, name: str, p: Protocol) -> tuple[Trial, bool]:
    """One push from the squeezed state; whether the simulation diverged in it (or before it)."""
    mujoco.mj_setState(sc.model, sc.data, squeezed.state, INTEGRATION)  # xfrc_applied back to zero too
    warned = diverged_count(sc)
    a = sc.object_qpos
    start_pos, start_quat = squeezed.start_pos, squeezed.start_quat
    sc.data.xfrc_applied[sc.object_body, :3] = p.force_factor * p.mass * direction
    steps = round(p.hold_seconds / p.timestep)
    moved, turned = 0.0, 0.0
    checks = max(1, steps // p.check_every)
    last_pos, last_quat, drift = start_pos, start_quat, []
    for done in range(1, checks + 1):
        mujoco.mj_step(sc.model, sc.data, nstep=p.check_every)
        pos, quat = sc.data.xipos[sc.object_body].copy(), sc.data.qpos[a + 3 : a + 7].copy()
        moved = float(np.linalg.norm(pos - start_pos))
        turned = _angle(start_quat, quat)
        if moved >= p.max_translation or turned >= p.max_rotation or not np.isfinite(moved):
            break
        if diverged_count(sc) > warned:
            break
        drift.append((float(np.linalg.norm(pos - last_pos)), _angle(last_quat, quat)))
        last_pos, last_quat = pos, quat
        if p.settle_checks and done >= 1 + p.settle_checks and _settled(moved, turned, drift, checks - done, p):
            break  # it will stay well inside the limits (`Protocol.settle_checks`): held
    diverged = squeezed.diverged or diverged_count(sc) > warned
    held = bool(np.isfinite(moved) and moved < p.max_translation and turned < p.max_rotation) and not diverged
    return Trial(name, moved if np.isfinite(moved) else float("inf"), turned, held), diverged


def _settled(moved: float, turned: float, drift: list[tuple[float, float]], left: int, p: Protocol) -> bool:
    """Whether the object, drifting no faster than over the last ``settle_checks`` checks for twice the ``left``
    checks, stays within half of the limits (``drift``: its motion (m, deg) in each check so far)."""
    recent = drift[-p.settle_checks :]
    speed = max(d for d, _ in recent)
    spin = max(r for _, r in recent)
    return bool(moved + 2 * left * speed < p.max_translation / 2 and turned + 2 * left * spin < p.max_rotation / 2)


def _angle(q1: np.ndarray, q2: np.ndarray) -> float:
    """Angle between two wxyz orientations, degrees."""
    dot = abs(float(np.dot(q1, q2)) / max(float(np.linalg.norm(q1) * np.linalg.norm(q2)), 1e-12))
    return float(np.degrees(2 * np.arccos(min(1.0, dot))))
