"""An in-memory `JobQueue` for the API-layer tests (routes, errors, auth, fuzz): no processes, instant.

Jobs finish at once with a small synthetic result unless ``hold`` is set (they stay queued until
`finish`). The end-to-end tests use the real backends instead.
"""

from __future__ import annotations

import asyncio
import time
import uuid

import numpy as np

from manifoundation.contract import (
    DeadLetter,
    ErrorBody,
    JobProgress,
    JobPublic,
    JobState,
    PhysicsQuality,
    PhysicsTrial,
    Proposal,
    Quality,
    QueueStats,
    RobotPublic,
    RobotRegister,
    Stage,
    SynthesisRequest,
    SynthesisResult,
    WorkerPublic,
)
from manifoundation.server.queue import JobNotFound, JobQueue, QueueFull, QueueUnavailable, RobotInvalid, RobotLimits
from manifoundation.server.queue.robot_quota import check

HAND = RobotPublic(
    name="fake_hand",
    builtin=True,
    dof=2,
    joint_names=["a", "b"],
    lower=[0.0, 0.0],
    upper=[1.0, 1.0],
    fingertips=["tip_a", "tip_b"],
    source="tests",
)


def _fake_physics() -> PhysicsQuality:
    """A simulated grasp test that held in five pushes and not in +z (what the viewer draws; no simulation here)."""
    pushes = ("-x", "+x", "-y", "+y", "-z")
    trials = [PhysicsTrial(direction=d, translation=0.002, rotation=1.5, held=True) for d in pushes]
    trials.append(PhysicsTrial(direction="+z", translation=0.08, rotation=30.0, held=False))
    return PhysicsQuality(held=False, reason="moved", trials=trials, penetration=0.0, tip_gaps=[0.0012, 0.0004],
                          touching_after_squeeze=2, seconds=0.1, object_pieces="hull")  # fmt: skip


def fake_result(request: SynthesisRequest) -> SynthesisResult:
    points = request.object.points
    contacts = points[[0, len(points) // 2]]
    normals = np.tile([0.0, 0.0, 1.0], (2, 1))
    proposal = Proposal(
        contact_points=contacts,
        contact_normals=normals,
        forces=-normals,
        fingertips=list(HAND.fingertips),
        palm_position=points.mean(axis=0) + np.array([0, 0, 0.1]),
        palm_quaternion=np.array([1.0, 0, 0, 0]),
        joint_names=list(HAND.joint_names),
        joint_values=np.array([0.1, 0.2]),
        quality=Quality(
            success=True,
            converged=True,
            reason="converged",
            iterations=3,
            wrench_residual=1e-8,
            max_tip_distance=0.001,
            penetration_depth=0.0,
            self_collision_depth=0.0,
            epsilon=0.1,
            physics=_fake_physics() if request.options.simulate else None,
        ),
    )
    heatmap = np.linspace(0, 1, len(points)) if request.options.return_heatmap else None
    return SynthesisResult(
        hand=request.robot.name or "inline",
        model_version="fake",
        proposals=[proposal],
        heatmap=heatmap,
        timings={"network": 0.01, "refinement": 0.02},
    )


class FakeQueue(JobQueue):
    backend = "fake"

    def __init__(self, *, hold: bool = False) -> None:
        self.hold = hold
        self.full = False
        self.down = False
        self.jobs: dict[str, JobPublic] = {}
        self.requests: dict[str, SynthesisRequest] = {}
        self.request_ids: dict[str, str | None] = {}  # job id -> the submitting request's id
        self.owners: dict[str, str | None] = {}  # job or batch id -> its owner
        self.batches: dict[str, list[str]] = {}
        self.robots = [HAND]
        self.started = self.closed = False

    def _check(self) -> None:
        if self.down:
            raise QueueUnavailable("fake queue is down")

    async def start(self) -> None:
        self.started = True

    async def close(self) -> None:
        self.closed = True

    async def ping(self) -> bool:
        return not self.down

    async def submit(
        self, requests: list[SynthesisRequest], *, batch_id: str | None = None, deadline: float | None = None,
        request_id: str | None = None, owner: str | None = None,
    ) -> list[str]:  # fmt: skip
        self._check()
        if self.full:
            raise QueueFull("fake queue is full", retry_after=2.5)
        ids = []
        for request in requests:
            job_id = uuid.uuid4().hex
            self.jobs[job_id] = JobPublic(
                id=job_id, state=JobState.QUEUED, created_at=time.time(), deadline=deadline, batch_id=batch_id
            )
            self.requests[job_id] = request
            self.request_ids[job_id] = request_id
            self.owners[job_id] = owner
            ids.append(job_id)
            if not self.hold:
                self.finish(job_id)
        return ids

    def finish(self, job_id: str, error: ErrorBody | None = None) -> None:
        job = self.jobs[job_id]
        job.started_at = job.finished_at = time.time()
        job.progress = JobProgress(stage=Stage.DONE, fraction=1.0)
        if error is None:
            job.state = JobState.SUCCEEDED
            job.result = fake_result(self.requests[job_id])
            job.timings = dict(job.result.timings)
        else:
            job.state = JobState.FAILED
            job.error = error

    async def get(self, job_id: str, *, with_result: bool = True, owner: str | None = None) -> JobPublic:
        self._check()
        if job_id not in self.jobs or (owner is not None and self.owners.get(job_id) != owner):
            raise JobNotFound(f"no job {job_id!r}")
        job = self.jobs[job_id]
        return job if with_result else job.model_copy(update={"result": None})

    async def wait(self, job_id: str, timeout: float) -> JobPublic:
        end = time.monotonic() + timeout
        while not (job := await self.get(job_id)).state.terminal and time.monotonic() < end:
            await asyncio.sleep(0.01)
        return job

    async def cancel(self, job_id: str, *, owner: str | None = None) -> JobPublic:
        job = await self.get(job_id, owner=owner)
        if not job.state.terminal:
            job.state = JobState.CANCELLED
            job.error = ErrorBody(error="job cancelled", type="Cancelled")
            job.finished_at = time.time()
        return job

    async def list_recent(self, limit: int = 50, *, owner: str | None = None) -> list[JobPublic]:
        self._check()
        mine = [j for j in self.jobs.values() if owner is None or self.owners.get(j.id) == owner]
        jobs = sorted(mine, key=lambda j: j.created_at, reverse=True)[:limit]
        return [j.model_copy(update={"result": None}) for j in jobs]

    async def create_batch(
        self, requests: list[SynthesisRequest], deadline: float | None = None, *, request_id: str | None = None,
        owner: str | None = None,
    ) -> str:  # fmt: skip
        batch_id = uuid.uuid4().hex
        ids = await self.submit(requests, batch_id=batch_id, deadline=deadline, request_id=request_id, owner=owner)
        self.batches[batch_id] = ids
        self.owners[batch_id] = owner
        return batch_id

    async def batch_job_ids(self, batch_id: str, *, owner: str | None = None) -> list[str]:
        self._check()
        if batch_id not in self.batches or (owner is not None and self.owners.get(batch_id) != owner):
            raise JobNotFound(f"no batch {batch_id!r}")
        return self.batches[batch_id]

    async def stats(self) -> QueueStats:
        self._check()
        by_state = {s: sum(1 for j in self.jobs.values() if j.state is s) for s in JobState}
        return QueueStats(
            depth=by_state[JobState.QUEUED],
            running=by_state[JobState.RUNNING],
            by_state=by_state,
            completed_total=by_state[JobState.SUCCEEDED],
            failed_total=by_state[JobState.FAILED],
            dead_letters=0,
            workers=1,
        )

    async def workers(self) -> list[WorkerPublic]:
        self._check()
        now = time.time()
        return [
            WorkerPublic(
                id="w1",
                host="localhost",
                pid=1,
                started_at=now,
                last_heartbeat=now,
                model_loaded=True,
                model_version="fake",
            )
        ]

    async def dead_letters(self, limit: int = 50) -> list[DeadLetter]:
        return []

    async def list_robots(self, *, owner: str | None = None) -> list[RobotPublic]:
        self._check()
        return [r for r in self.robots if r.builtin or self.owners.get("robot:" + r.name) == owner]

    async def register_robot(
        self,
        robot: RobotRegister,
        timeout: float = 30.0,
        *,
        owner: str | None = None,
        limits: RobotLimits | None = None,
    ) -> RobotPublic:
        if limits is not None:  # the real rule, on this fake's robots (nothing runs concurrently here)
            mine = [r for r in self.robots if not r.builtin and self.owners.get("robot:" + r.name) == owner]
            check({r.name: r.stored_bytes or 0 for r in mine}, [], robot.name, robot.stored_bytes, limits)
        if robot.urdf is not None and "<robot" not in robot.urdf:
            raise RobotInvalid("malformed URDF: no <robot> element")
        public = RobotPublic(
            name=robot.name,
            builtin=False,
            dof=0,
            joint_names=[],
            lower=[],
            upper=[],
            fingertips=list(robot.fingertips or []),
            source="user",
            stored_bytes=robot.stored_bytes,
        )
        self.robots.append(public)
        self.owners["robot:" + robot.name] = owner
        return public
