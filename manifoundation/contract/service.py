"""What the service answers besides jobs and results: health, lists, the dashboard's data, a result's scene.

Defined here, in the contract, so that the SDK reads the shapes the service sends instead of guessing them.
"""

from __future__ import annotations

from typing import Literal

from pydantic import Field

from manifoundation.contract.common import WireModel
from manifoundation.contract.jobs import DeadLetter, JobPublic, WorkerPublic
from manifoundation.contract.robots import RobotPublic
from manifoundation.contract.states import JobState


class HealthPublic(WireModel):
    """Answer of ``GET /healthz`` (service-local: liveness only)."""

    status: str = "ok"
    backend: str
    version: str = Field(..., description="The service's own version (its distribution's).")
    contract_version: str | None = Field(
        None, description="The wire contract's MAJOR.MINOR (docs/compatibility.md); None: older than the handshake."
    )


class JobList(WireModel):
    """Answer of ``GET /v1/jobs``: the most recent jobs, newest first, without results (service-local)."""

    jobs: list[JobPublic]


class RobotList(WireModel):
    """Answer of ``GET /v1/robots``: the built-in hands and the caller's registered ones."""

    robots: list[RobotPublic]


class QueueStats(WireModel):
    """Counters for the dashboard and `/metrics`."""

    depth: int = Field(..., description="Jobs waiting to be picked up.")
    running: int
    by_state: dict[JobState, int]
    completed_total: int
    failed_total: int
    dead_letters: int
    workers: int


class Sample(WireModel):
    """The queue at one moment."""

    t: float
    depth: int
    running: int
    by_state: dict[JobState, int]
    completed_total: int
    failed_total: int


class DashboardPublic(WireModel):
    """Answer of ``GET /dashboard/data``."""

    now: float
    backend: str
    queue_up: bool
    stats: QueueStats | None = None
    throughput_per_s: float = Field(0.0, description="Jobs finished per second over the last minute.")
    latency_p50: float | None = Field(None, description="Submission → finish of recent jobs, s.")
    latency_p99: float | None = None
    finished_jobs: int = Field(0, description="Synthesis jobs among the recent ones (`recent`'s window, up to 200) "
                               "that finished: succeeded or failed.")  # fmt: skip
    verified_grasps: int = Field(0, description="Of `finished_jobs`, those whose best proposal is verified.")
    verified_rate: float | None = Field(None, description="verified_grasps / finished_jobs; None: none finished.")
    series: list[Sample] = Field(default_factory=list)
    workers: list[WorkerPublic] = Field(default_factory=list)
    recent: list[JobPublic] = Field(default_factory=list)
    dead_letters: list[DeadLetter] = Field(default_factory=list)


class SceneObstacle(WireModel):
    """One obstacle of a plan's scene as the viewer draws it, world frame (m): a triangle mesh (boxes and meshes),
    or points (point clouds, and meshes too large to draw)."""

    name: str
    kind: Literal["box", "mesh", "points"]
    vertices: list[list[float]]
    faces: list[list[int]] | None = None


class ScenePublic(WireModel):
    """Answer of ``GET /v1/jobs/{id}/scene``: the job (with result) and the object to draw it on; for a plan
    job also the scene's obstacles and support plane (the object's points are then in its own frame: the plan's
    poses place them)."""

    job: JobPublic
    points: list[list[float]] | None = Field(None, description="Subsampled object points (≤ 4096), m.")
    normals: list[list[float]] | None = None
    region_mask: list[int] | None = None
    heatmap: list[float] | None = Field(None, description="Contact heatmap at those points (return_heatmap).")
    target_points: list[list[float]] | None = Field(
        None, description="Per-point tasks: where those points should go (or the unordered target cloud), m."
    )
    obstacles: list[SceneObstacle] | None = Field(None, description="A plan's obstacles, world frame.")
    support_height: float | None = Field(None, description="A plan's support plane z = height, m.")
    waypoints: list[list[float]] | None = Field(None, description="A plan's requested waypoint positions, m.")
