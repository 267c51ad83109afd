"""The object's motion between two poses: OMPL RRT-Connect in SE(3), the scene checked with fcl.

- The state space is OMPL's ``SE3StateSpace`` bounded by the box around the start and waypoints (plus a margin).
  Its rotation distance is weighted by twice the object's radius, so one unit of SE(3) distance is about one
  metre travelled by the object's farthest point (OMPL's SO(3) distance is half the rotation angle).
- Validity: `CollisionScene.object_free` through ``SpaceInformation.setStateValidityChecker`` (``SimpleSetup``
  with a Python checker raised ``std::bad_cast`` when measured); motions are checked every
  ``collision_resolution`` of that distance.
- A segment whose straight motion is free is kept straight: no planner call, so a free path stays a line.
  Otherwise RRT-Connect runs until it connects or its time is up; its path is simplified with OMPL's
  ``PathSimplifier.simplifyMax`` (vertex reduction, shortcuts, close-vertex collapse: fixed iteration counts,
  so it does not depend on the wall clock).
- Determinism: OMPL draws every sampler's seed from one generator; ``RNG.setSeed`` re-seeds it before each
  segment (OMPL logs that sampling "already started" on the second call: it still re-seeds, which the tests
  check, so OMPL's log is silenced). Same seed, same path, unless the time limit cuts a search short.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from ompl import base as ob
from ompl import geometric as og
from ompl import util as ou

from manifoundation.core.planning.poses import Pose

ou.setLogLevel(ou.LogLevel.LOG_NONE)


@dataclass
class SegmentPath:
    """The vertices of one segment's path (first = source, last = target) and how they were found."""

    poses: list[Pose]
    straight: bool
    planner_seconds: float
    simplify_seconds: float
    raw_states: int
    solved: bool


def _state(space: ob.SE3StateSpace, pose: Pose) -> ob.State:
    state = space.allocState()
    x, y, z = (float(v) for v in pose.position)
    state.setXYZ(x, y, z)
    rot = state.rotation()
    w, qx, qy, qz = (float(v) for v in pose.quaternion)
    rot.w, rot.x, rot.y, rot.z = w, qx, qy, qz
    return state


def _pose(state: ob.State) -> Pose:
    rot = state.rotation()
    quat = np.array([rot.w, rot.x, rot.y, rot.z], dtype=np.float64)
    return Pose(np.array([state.getX(), state.getY(), state.getZ()]), quat / np.linalg.norm(quat))


def ompl_seed(seed: int, segment: int) -> int:
    """The OMPL seed of a segment (never 0, which OMPL refuses)."""
    return 1 + (seed * 7919 + segment) % (2**31 - 2)


class SegmentPlanner:
    """Plans segments in one bounded SE(3) space against one validity test.

    Args:
        is_free: the object's collision test at a pose (`CollisionScene.object_free`).
        lower, upper: (3,) the sampling box of the object's position (m).
        radius: the object's radius (m), the rotation distance's weight.
        resolution: SE(3) distance (m) between two collision checks along a motion.
    """

    def __init__(
        self, is_free: Callable[[Pose], bool], lower: np.ndarray, upper: np.ndarray, radius: float, resolution: float
    ) -> None:
        self.space = ob.SE3StateSpace()
        bounds = ob.RealVectorBounds(3)
        for i in range(3):
            bounds.setLow(i, float(lower[i]))
            bounds.setHigh(i, float(upper[i]))
        self.space.setBounds(bounds)
        self.space.setSubspaceWeight(1, 2.0 * max(radius, 1e-3))
        self.si = ob.SpaceInformation(self.space)
        self.checks = 0

        def valid(state: ob.State) -> bool:
            self.checks += 1
            return bool(self.space.satisfiesBounds(state)) and is_free(_pose(state))

        self._valid = valid  # kept alive: OMPL holds only a reference to the callable
        self.si.setStateValidityChecker(valid)
        self.si.setStateValidityCheckingResolution(min(1.0, resolution / self.space.getMaximumExtent()))
        self.si.setup()

    def straight_free(self, source: Pose, target: Pose) -> bool:
        """Whether the straight motion source → target is collision-free at the checking resolution."""
        return bool(self.si.checkMotion(_state(self.space, source), _state(self.space, target)))

    def plan(self, source: Pose, target: Pose, seconds: float, seed: int, simplify: bool = True) -> SegmentPath:
        """The path source → target: straight when free, else RRT-Connect (seeded) and simplification.

        Returns:
            The path; ``solved`` False when RRT-Connect ran out of time (``poses`` then holds only the ends).
        """
        if self.straight_free(source, target):
            return SegmentPath([source, target], True, 0.0, 0.0, 2, True)
        ou.RNG.setSeed(seed)
        pdef = ob.ProblemDefinition(self.si)
        pdef.setStartAndGoalStates(_state(self.space, source), _state(self.space, target))
        planner = og.RRTConnect(self.si)
        planner.setProblemDefinition(pdef)
        planner.setup()
        t0 = time.perf_counter()
        planner.solve(float(seconds))
        planner_s = time.perf_counter() - t0
        if not pdef.hasExactSolution():
            return SegmentPath([source, target], False, planner_s, 0.0, 0, False)
        path = pdef.getSolutionPath()
        raw = int(path.getStateCount())
        t0 = time.perf_counter()
        if simplify:
            og.PathSimplifier(self.si).simplifyMax(path)
        simplify_s = time.perf_counter() - t0
        poses = [_pose(s) for s in path.getStates()]
        poses[0], poses[-1] = source, target  # exactly the requested ends (OMPL copies them in float64 anyway)
        return SegmentPath(poses, False, planner_s, simplify_s, raw, True)
