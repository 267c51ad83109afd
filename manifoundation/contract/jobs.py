"""Jobs, batches and workers: the asynchronous side of the API."""

from __future__ import annotations

from pydantic import Field

from manifoundation.contract.common import WireModel
from manifoundation.contract.errors import ErrorBody
from manifoundation.contract.plans import PlanRequest, PlanResult
from manifoundation.contract.requests import SynthesisRequest
from manifoundation.contract.results import SynthesisResult
from manifoundation.contract.states import JobKind, JobState, Stage

MAX_BATCH_SIZE = 1000

JobRequest = SynthesisRequest | PlanRequest
"""What a job is submitted with; its kind is `kind_of` it."""


def kind_of(request: JobRequest) -> JobKind:
    """The kind of job ``request`` makes."""
    return JobKind.PLAN if isinstance(request, PlanRequest) else JobKind.SYNTHESIS


class JobProgress(WireModel):
    """Progress of a job: its stage, and the refinement iteration when refining; for a plan, how many of the
    stage's items (waypoints checked, segments planned, steps synthesised) are done."""

    stage: Stage = Stage.QUEUED
    fraction: float = Field(0.0, ge=0, le=1)
    iteration: int | None = None
    max_iterations: int | None = None
    completed: int | None = Field(None, ge=0, description="Plans: items of the stage done.")
    total: int | None = Field(None, ge=0, description="Plans: items of the stage (waypoints, segments, steps).")


class JobPublic(WireModel):
    """A job as the API shows it: a synthesis job answers ``result``, a plan job ``plan``."""

    id: str
    kind: JobKind = JobKind.SYNTHESIS
    state: JobState
    progress: JobProgress = Field(default_factory=JobProgress)
    created_at: float = Field(..., description="Unix time, seconds.")
    started_at: float | None = None
    finished_at: float | None = None
    deadline: float | None = Field(None, description="Unix time after which the job is dropped.")
    deliveries: int = Field(0, ge=0, description="Times a worker took the job.")
    worker: str | None = None
    batch_id: str | None = None
    timings: dict[str, float] = Field(default_factory=dict)
    result: SynthesisResult | None = None
    plan: PlanResult | None = Field(None, description="A plan job's answer.")
    error: ErrorBody | None = None


class JobCreated(WireModel):
    """Answer of ``POST /v1/jobs`` (and of a synthesize call that outlived its wait): 202."""

    id: str
    state: JobState
    url: str


class BatchCreate(WireModel):
    """Body of ``POST /v1/batches``."""

    requests: list[SynthesisRequest] = Field(..., min_length=1, max_length=MAX_BATCH_SIZE)


class BatchItem(WireModel):
    """One request of a batch."""

    index: int
    job_id: str
    state: JobState
    result: SynthesisResult | None = None
    error: ErrorBody | None = None


class BatchPublic(WireModel):
    """A batch: counts by state, and one page of its items in request order."""

    id: str
    total: int
    counts: dict[JobState, int]
    done: bool
    items: list[BatchItem]
    offset: int = 0
    limit: int = 100
    created_at: float


class WorkerPublic(WireModel):
    """A worker process as seen through its heartbeats."""

    id: str
    host: str
    pid: int
    started_at: float
    last_heartbeat: float
    current_job: str | None = None
    jobs_done: int = 0
    model_loaded: bool = False
    model_version: str | None = None


class DeadLetter(WireModel):
    """A job that failed on every delivery and was set aside with its last error."""

    job_id: str
    deliveries: int
    error: ErrorBody
    failed_at: float


class ReadyPublic(WireModel):
    """Answer of ``GET /readyz``."""

    ready: bool
    queue: bool
    workers: int
    model_loaded: bool
    detail: str | None = None
