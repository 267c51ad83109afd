"""`simulate(body, contacts, motions) -> Rollout`: grasp points of a deformable body and move them, on MuJoCo.

Schedule: the grasped vertices follow their paths for ``move_seconds``, are released (the grasp equalities switch
off; a plasticine base stays held by the board, `mjcf.held_vertices`) and the body settles for ``settle_seconds``;
the rollout is the cloud (surface vertices) then. A contact's path from its start p₀ with motion d is p(s) = p₀ +
σ(s) d + ẑ · lift · |d| · sin(π σ(s)), σ the minimum-jerk profile 10s³ − 15s⁴ + 6s⁵ of s = t / move_seconds: a
straight drag that rises by ``lift``·|d| in the middle (cloth folds lift the edge over the cloth; a plasticine press
does not lift). Data generation and the evaluation both call this function, so a label and its check see the same
physics.
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from manifoundation.core.deformable.body import DeformableBody
from manifoundation.core.deformable.metrics import ShapeScore, shape_score
from manifoundation.core.deformable.mjcf import FLEX_NAME, scene_xml

LIFT = {"cloth": 0.3, "rope": 0.1, "plasticine": 0.0}
TIMESTEP = {"cloth": 0.01, "rope": 0.01, "plasticine": 0.01}
log = logging.getLogger("manifoundation.core.deformable")


@dataclass(frozen=True)
class SimConfig:
    """Simulation schedule; ``lift`` and ``timestep`` default per material (`LIFT`, `TIMESTEP`)."""

    move_seconds: float = 1.0
    settle_seconds: float = 0.5
    lift: float | None = None
    timestep: float | None = None


@dataclass
class Rollout:
    """A simulation's outcome.

    Attributes:
        cloud: (N, 3) final positions of the body's cloud points.
        vertices: (V, 3) final positions of every vertex.
        stable: no NaN, no MuJoCo reset (bad accelerations) and no vertex flung farther than twice the body's
            size plus the largest motion during the run.
        tracking_error: largest distance (m) between a grasped vertex and its path's end when released.
        steps: physics steps taken. seconds: wall time of the stepping.
    """

    cloud: np.ndarray
    vertices: np.ndarray
    stable: bool
    tracking_error: float
    steps: int
    seconds: float

    def score(self, body: DeformableBody, target: np.ndarray) -> ShapeScore:
        """This rollout's cloud of ``body`` against ``target`` (N, 3) by the paper's metric (an unstable rollout
        is scored on its last finite state)."""
        return shape_score(body.material, body.points, target, self.cloud)

    def reaches(self, body: DeformableBody, target: np.ndarray) -> bool:
        """Whether this rollout of ``body`` is stable and reaches ``target`` (N, 3) by the paper's metric."""
        return bool(self.stable and self.score(body, target).success)


def minimum_jerk(s: np.ndarray | float) -> np.ndarray:
    """σ(s) = 10s³ − 15s⁴ + 6s⁵ on s clipped to [0, 1]."""
    s = np.clip(np.asarray(s, dtype=np.float64), 0.0, 1.0)
    sigma: np.ndarray = s**3 * (10 - 15 * s + 6 * s**2)
    return sigma


def path_points(start: np.ndarray, motion: np.ndarray, s: float, lift: float) -> np.ndarray:
    """(H, 3) positions on the contacts' paths at phase ``s`` ∈ [0, 1] (see the module doc)."""
    sigma = float(minimum_jerk(s))
    rise = lift * np.linalg.norm(motion, axis=1, keepdims=True) * np.sin(np.pi * sigma)
    points: np.ndarray = start + sigma * motion + rise * np.array([0.0, 0.0, 1.0])
    return points


def contact_vertices(body: DeformableBody, contacts: np.ndarray) -> np.ndarray:
    """Cloud indices (H,) of the cloud points nearest to ``contacts`` (H, 3) m, or the indices themselves (H,)."""
    c = np.asarray(contacts)
    if c.ndim == 1 and np.issubdtype(c.dtype, np.integer):
        if c.min(initial=0) < 0 or c.max(initial=0) >= len(body.surface):
            raise ValueError(f"contacts: indices outside 0..{len(body.surface) - 1}")
        return c.astype(np.int64)
    c = np.asarray(contacts, dtype=np.float64).reshape(-1, 3)
    nearest: np.ndarray = cKDTree(body.points).query(c)[1].astype(np.int64)
    return nearest


def simulate(body: DeformableBody, contacts: np.ndarray, motions: np.ndarray,
             config: SimConfig | None = None) -> Rollout:  # fmt: skip
    """Grasp ``contacts`` on ``body``, move each by its motion, release, settle; return the rollout.

    Args:
        body: the deformable body at rest.
        contacts: (H, 3) points (snapped to the nearest cloud point) or (H,) cloud indices.
        motions: (H, 3) post-contact motion of each contact, m (world frame).
        config: schedule (default `SimConfig()`).

    Returns:
        The rollout; ``stable`` is False when MuJoCo had to reset (its cloud is then the last finite state).

    Raises:
        ValueError: contacts and motions of different lengths, or non-finite motions.
    """
    import mujoco

    cfg = config or SimConfig()
    idx = contact_vertices(body, contacts)
    mot = np.asarray(motions, dtype=np.float64).reshape(-1, 3)
    if len(mot) != len(idx):
        raise ValueError(f"motions: {len(mot)} rows for {len(idx)} contacts")
    if not np.all(np.isfinite(mot)):
        raise ValueError("motions: NaN or inf")
    # one grasp per vertex: contacts on the same point share the mean of their motions
    verts, inverse = np.unique(body.surface[idx], return_inverse=True)
    mot = np.stack([mot[inverse == k].mean(axis=0) for k in range(len(verts))]) if len(idx) else mot
    dt = cfg.timestep or TIMESTEP[body.material]
    lift = LIFT[body.material] if cfg.lift is None else cfg.lift
    bad = [int(w) for w in (mujoco.mjtWarning.mjWARN_BADQPOS, mujoco.mjtWarning.mjWARN_BADQVEL,
                            mujoco.mjtWarning.mjWARN_BADQACC)]  # MuJoCo resets the state after these
    start = np.asarray(body.vertices, dtype=np.float64)[verts]
    move, settle = round(cfg.move_seconds / dt), round(cfg.settle_seconds / dt)
    previous = mujoco.get_mju_user_warning()
    mujoco.set_mju_user_warning(lambda message: log.debug("mujoco: %s", message))  # counted in data.warning
    t0 = time.perf_counter()
    rest = np.asarray(body.vertices, dtype=np.float64)
    last_good, reached = rest, start
    # no vertex can honestly end farther from rest than the largest motion plus the body's own size (twice)
    reach = 2.0 * (body.size + float(np.linalg.norm(mot, axis=1).max(initial=0.0)))
    stable, k = True, -1
    try:
        model = mujoco.MjModel.from_xml_string(scene_xml(body, verts, dt))
        data = mujoco.MjData(model)
        mujoco.mj_forward(model, data)
        last_good = data.flexvert_xpos.copy()
        for k in range(move + settle):
            if k < move and len(verts):
                data.mocap_pos[:] = path_points(start, mot, (k + 1) / move, lift)
            if k == move:
                data.eq_active[: len(verts)] = 0  # the grasps let go; the board keeps its hold (mjcf)
            mujoco.mj_step(model, data)
            if k == move - 1:
                reached = data.flexvert_xpos[verts].copy()
            if any(data.warning[w].number for w in bad) or not np.all(np.isfinite(data.flexvert_xpos)):
                stable = False
                break
            if k % 10 == 0:
                if np.abs(data.flexvert_xpos - rest).max() > reach:  # flung away: a silent blow-up
                    stable = False
                    break
                last_good = data.flexvert_xpos.copy()
        else:
            last_good = data.flexvert_xpos.copy()
    finally:
        mujoco.set_mju_user_warning(previous)
    seconds = time.perf_counter() - t0
    goal = start + mot
    err = float(np.linalg.norm(reached - goal, axis=1).max(initial=0.0)) if stable else float("inf")
    vertices = np.asarray(last_good, dtype=np.float64)
    return Rollout(vertices[body.surface], vertices, stable, err, k + 1, seconds)


__all__ = ["FLEX_NAME", "Rollout", "SimConfig", "contact_vertices", "minimum_jerk", "path_points", "simulate"]
