"""`StagedPipeline`: a small, real, science-free pipeline for queue tests and benchmarks.

It walks a job through the real stage sequence (network for the whole micro-batch at once, then per job:
initialisation, refinement k/max, verification) sleeping ``stage_seconds`` per stage, honours cancellation between
stages and deadlines, and answers a `SynthesisResult` with no proposals and ``model_version`` "staged-test"; a plan
job walks repair, planning (one stage time per segment) and contacts, and answers the straight poses start →
waypoints with no steps. It is NOT the science: it exists so the queue mechanics can be tested the way arq tests use
a burst worker. Fault injection for tests: a request whose ``options.seed`` equals ``crash_seed`` kills its worker
process (SIGKILL), one equal to ``fail_seed`` raises; a registration of the robot named ``slow_robot`` takes
``robot_seconds`` to load (in Python, a little at a time: a loader that outlives its deadline). A job given a registered
robot reports its joint count as ``timings["robot_dof"]``, so tests can tell which registration (whose URDF) a job ran
with.
"""

from __future__ import annotations

import os
import signal
import time
import xml.etree.ElementTree as ET

import numpy as np

from manifoundation.contract import PlanResult, RobotPreview, RobotPublic, RobotRegister, Stage, SynthesisResult
from manifoundation.server.queue.records import cancelled_error, deadline_error
from manifoundation.server.worker.pipeline import (
    CancelFn,
    JobInput,
    Outcome,
    PlanJob,
    PlanOutcome,
    PlanProgressFn,
    ProgressFn,
)

TEST_HAND = RobotPublic(
    name="test_gripper",
    builtin=True,
    dof=1,
    joint_names=["finger"],
    lower=[0.0],
    upper=[0.04],
    fingertips=["left_tip", "right_tip"],
    source="research.staged_pipeline",
)


_TETRAHEDRON = RobotPreview(
    vertices=np.array([[0.0, 0, 0], [0.02, 0, 0], [0, 0.02, 0], [0, 0, 0.02]]),
    faces=np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]),
    spheres=np.array([[0.005, 0.005, 0.005, 0.01]]),
    pads=np.array([[0.0, 0.0, 0.02]]),
    tips=np.array([[0.0, 0.0, 0.02]]),
)
"""What a registered hand's view draws in the staged pipeline (it builds no hand)."""


class StagedPipeline:
    """Stage-walking test pipeline (see module doc)."""

    model_version: str | None = "staged-test"

    def __init__(
        self,
        stage_seconds: float = 0.0,
        batch_seconds: float | None = None,
        iterations: int = 3,
        crash_seed: int | None = None,
        fail_seed: int | None = None,
        model_loaded: bool = True,
        slow_robot: str | None = None,
        robot_seconds: float = 0.0,
    ) -> None:
        self.stage_seconds = stage_seconds
        self.batch_seconds = stage_seconds if batch_seconds is None else batch_seconds
        self.iterations = iterations
        self.crash_seed = crash_seed
        self.fail_seed = fail_seed
        self.model_loaded = model_loaded
        self.slow_robot = slow_robot
        self.robot_seconds = robot_seconds

    def robots(self) -> list[RobotPublic]:
        return [TEST_HAND]

    def validate_robot(self, robot: RobotRegister) -> RobotPublic:
        if robot.name == self.slow_robot:
            end = time.monotonic() + self.robot_seconds
            while time.monotonic() < end:
                time.sleep(0.01)
        try:
            root = ET.fromstring(robot.urdf or robot.mjcf or "")
        except ET.ParseError as exc:
            raise ValueError(f"urdf: malformed XML: {exc}") from exc
        if root.tag != "robot":
            raise ValueError("urdf: root element must be <robot>")
        links = {link.get("name") for link in root.iter("link")}
        missing = [tip for tip in robot.fingertips or [] if tip not in links]
        if missing:
            raise ValueError(f"fingertips: unknown links {missing}")
        joints = [j.get("name") or "" for j in root.iter("joint") if j.get("type") in ("revolute", "prismatic")]
        return RobotPublic(
            name=robot.name,
            builtin=False,
            dof=len(joints),
            joint_names=joints,
            lower=[0.0] * len(joints),
            upper=[1.0] * len(joints),
            fingertips=list(robot.fingertips or []),
            source="user",
            preview=_TETRAHEDRON,
        )

    def run(self, jobs: list[JobInput], progress: ProgressFn, should_cancel: CancelFn) -> list[Outcome]:
        for job in jobs:
            seed = job.request.options.seed
            if self.crash_seed is not None and seed == self.crash_seed:
                os.kill(os.getpid(), signal.SIGKILL)
            if self.fail_seed is not None and seed == self.fail_seed:
                raise RuntimeError(f"injected failure (seed {seed})")
            progress(job.id, Stage.NETWORK, 0.0, None, None)
        t0 = time.perf_counter()
        time.sleep(self.batch_seconds)
        network = time.perf_counter() - t0
        return [self._one(job, network, progress, should_cancel) for job in jobs]

    def _one(self, job: JobInput, network: float, progress: ProgressFn, should_cancel: CancelFn) -> Outcome:
        timings = {"network": network}
        iterations = min(self.iterations, job.request.options.max_iterations)
        steps: list[tuple[Stage, int | None]] = [(Stage.INITIALISATION, None)]
        steps += [(Stage.REFINEMENT, k) for k in range(1, iterations + 1)]
        steps.append((Stage.VERIFICATION, None))
        for i, (stage, k) in enumerate(steps):
            if should_cancel(job.id):
                return cancelled_error()
            if job.deadline is not None and time.time() > job.deadline:
                return deadline_error("while it ran")
            progress(job.id, stage, i / len(steps), k, iterations if k else None)
            t0 = time.perf_counter()
            time.sleep(self.stage_seconds)
            timings[stage.value] = timings.get(stage.value, 0.0) + time.perf_counter() - t0
        hand = "none" if job.request.robot is None else job.request.robot.name or "inline"
        if job.robot is not None:
            root = ET.fromstring(job.robot.urdf or job.robot.mjcf or "<robot/>")
            timings["robot_dof"] = float(sum(j.get("type") in ("revolute", "prismatic") for j in root.iter("joint")))
        return SynthesisResult(hand=hand, model_version=self.model_version or "", proposals=[], timings=timings)

    def plan(self, job: PlanJob, progress: PlanProgressFn, should_cancel: CancelFn) -> PlanOutcome:
        request = job.request
        seed = request.options.seed
        if self.crash_seed is not None and seed == self.crash_seed:
            os.kill(os.getpid(), signal.SIGKILL)
        if self.fail_seed is not None and seed == self.fail_seed:
            raise RuntimeError(f"injected failure (seed {seed})")
        segments = len(request.waypoints)
        stages = [(Stage.REPAIR, 1, 1)] + [(Stage.PLANNING, k, segments) for k in range(1, segments + 1)]
        stages.append((Stage.CONTACTS, 1, 1))
        t0 = time.perf_counter()
        for stage, completed, total in stages:
            if should_cancel(job.id):
                return cancelled_error()
            if job.deadline is not None and time.time() > job.deadline:
                return deadline_error("while it ran")
            progress(job.id, stage, completed, total)
            time.sleep(self.stage_seconds)
        poses = [request.start, *request.waypoints]
        return PlanResult(
            success=True, positions=np.array([p.position for p in poses]),
            quaternions=np.array([p.quaternion for p in poses]), waypoint_indices=list(range(1, len(poses))),
            hand=request.robot.name or "inline", model_version=self.model_version,
            timings={"planning": time.perf_counter() - t0},
        )  # fmt: skip
