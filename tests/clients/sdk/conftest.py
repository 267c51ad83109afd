"""A fake service for the SDK's I/O-free core: an ``httpx.MockTransport`` answering real encoded contract bodies.

It implements the v1 routes in memory (jobs finish after a set number of polls), decodes request bodies with the
contract's codec and answers in the encoding the Accept header asks for, so the SDK is exercised end to end
without a server. Tests against the real service live in ``test_service_e2e.py``.
"""

from __future__ import annotations

import itertools
import json
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from typing import Any

import httpx
import numpy as np
import pytest

from clients.codec import decode_body, dump_model, media_type
from clients.schemas import (
    BatchCreate,
    BatchItem,
    BatchPublic,
    ErrorBody,
    FieldError,
    JobCreated,
    JobPublic,
    JobState,
    Proposal,
    Quality,
    ReadyPublic,
    RobotPublic,
    RobotRegister,
    SynthesisRequest,
    SynthesisResult,
    WireModel,
)


def sample_result(hand: str = "leap", contacts: int = 4, seed: int = 0) -> SynthesisResult:
    """A plausible result with numpy arrays (what a worker would produce)."""
    rng = np.random.default_rng(seed)
    points = rng.normal(size=(contacts, 3)) * 0.03
    normals = points / np.linalg.norm(points, axis=1, keepdims=True)
    proposal = Proposal(
        contact_points=points,
        contact_normals=normals,
        forces=-normals * 2.0,
        fingertips=[f"tip_{i}" for i in range(contacts)],
        palm_position=np.array([0.0, 0.0, 0.12]),
        palm_quaternion=np.array([1.0, 0.0, 0.0, 0.0]),
        joint_names=[f"j{i}" for i in range(16)],
        joint_values=np.linspace(0, 1, 16),
        quality=Quality(
            success=True,
            converged=True,
            reason="converged",
            iterations=12,
            wrench_residual=1e-8,
            max_tip_distance=0.001,
            penetration_depth=0.0,
            self_collision_depth=0.0,
            epsilon=0.05,
        ),
    )
    return SynthesisResult(hand=hand, model_version="test", proposals=[proposal], timings={"refinement": 0.1})


def sample_object_points(n: int = 256, seed: int = 0) -> np.ndarray:
    """(n, 6) points and outward normals on a 5 cm sphere."""
    rng = np.random.default_rng(seed)
    normals = rng.normal(size=(n, 3))
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    return np.hstack([normals * 0.05, normals])


@dataclass
class FakeJob:
    job: JobPublic
    request: SynthesisRequest
    polls_left: int


@dataclass
class FakeService:
    """In-memory v1 API. ``polls_to_finish``: GETs of a job before it succeeds; ``fail``: jobs end failed."""

    polls_to_finish: int = 0
    sync_finishes: bool = True
    fail: bool = False
    api_key: str | None = None
    script: list[httpx.Response | Exception] = field(default_factory=list)
    seen: list[httpx.Request] = field(default_factory=list)
    jobs: dict[str, FakeJob] = field(default_factory=dict)
    batches: dict[str, list[str]] = field(default_factory=dict)
    robots: dict[str, RobotPublic] = field(default_factory=dict)
    _ids: itertools.count[int] = field(default_factory=itertools.count)

    # ---- plumbing ---------------------------------------------------------------------------------------

    def transport(self) -> httpx.MockTransport:
        return httpx.MockTransport(self.handle)

    def handle(self, request: httpx.Request) -> httpx.Response:
        self.seen.append(request)
        if self.script:  # scripted answers first (errors, 429s, connection failures)
            step = self.script.pop(0)
            if isinstance(step, Exception):
                raise step
            return step
        if self.api_key and request.headers.get("authorization") != f"Bearer {self.api_key}":
            return self.error(request, 401, "missing or unknown API key", "Unauthorized")
        return self.route(request)

    def answer(self, request: httpx.Request, model: Any, status: int = 200) -> httpx.Response:
        kind = media_type(request.headers.get("accept"))
        return httpx.Response(status, content=dump_model(model, kind), headers={"content-type": kind})

    def error(self, request: httpx.Request, status: int, message: str, type: str, **kw: Any) -> httpx.Response:
        return self.answer(request, ErrorBody(error=message, type=type, **kw), status)

    def body(self, request: httpx.Request, cls: type[Any]) -> Any:
        return cls.model_validate(decode_body(request.content, request.headers.get("content-type")))

    # ---- jobs -------------------------------------------------------------------------------------------

    def new_job(self, req: SynthesisRequest, batch_id: str | None = None) -> FakeJob:
        job_id = f"job-{next(self._ids)}"
        job = JobPublic(id=job_id, state=JobState.QUEUED, created_at=time.time(), batch_id=batch_id)
        fake = FakeJob(job, req, self.polls_to_finish)
        self.jobs[job_id] = fake
        return fake

    def advance(self, fake: FakeJob) -> JobPublic:
        if fake.job.state.terminal:
            return fake.job
        if fake.polls_left > 0:
            fake.polls_left -= 1
            fake.job = fake.job.model_copy(update={"state": JobState.RUNNING})
            return fake.job
        if self.fail:
            error = ErrorBody(error="refinement diverged", type="InternalError")
            fake.job = fake.job.model_copy(update={"state": JobState.FAILED, "error": error})
        else:
            result = sample_result(fake.request.robot.name or "custom", seed=int(fake.job.id.split("-")[1]))
            fake.job = fake.job.model_copy(update={"state": JobState.SUCCEEDED, "result": result})
        return fake.job

    # ---- routes -----------------------------------------------------------------------------------------

    def route(self, request: httpx.Request) -> httpx.Response:
        path, method = request.url.path, request.method
        parts = path.strip("/").split("/")
        if path == "/healthz":
            return httpx.Response(200, json={"status": "ok"})
        if path == "/readyz":
            ready = ReadyPublic(ready=True, queue=True, workers=2, model_loaded=True)
            return self.answer(request, ready)
        if path == "/v1/synthesize" and method == "POST":
            req = self.body(request, SynthesisRequest)
            fake = self.new_job(req)
            if self.sync_finishes:
                job = self.advance(fake)
                if job.result is not None:
                    return self.answer(request, job.result)
                if job.error is not None:  # the service answers a finished job's error with its id
                    response = self.answer(request, job.error, 422)
                    response.headers["X-Job-ID"] = job.id
                    return response
            url = f"http://testserver/v1/jobs/{fake.job.id}"
            return self.answer(request, JobCreated(id=fake.job.id, state=fake.job.state, url=url), 202)
        if path == "/v1/jobs" and method == "POST":
            fake = self.new_job(self.body(request, SynthesisRequest))
            return self.answer(request, JobCreated(id=fake.job.id, state=JobState.QUEUED, url="x"), 202)
        if path == "/v1/jobs" and method == "GET":
            jobs = [f.job.model_copy(update={"result": None}) for f in reversed(self.jobs.values())]
            return httpx.Response(200, json={"jobs": [j.model_dump(mode="json", exclude_none=True) for j in jobs]})
        if parts[:2] == ["v1", "jobs"] and len(parts) >= 3:
            fake = self.jobs.get(parts[2])
            if fake is None:
                return self.error(request, 404, f"no job {parts[2]!r}", "NotFound")
            if len(parts) == 4 and parts[3] == "events":
                return self.sse(fake)
            if method == "DELETE":
                if not fake.job.state.terminal:
                    fake.job = fake.job.model_copy(update={"state": JobState.CANCELLED})
                return self.answer(request, fake.job)
            return self.answer(request, self.advance(fake))
        if path == "/v1/batches" and method == "POST":
            body = self.body(request, BatchCreate)
            batch_id = f"batch-{next(self._ids)}"
            self.batches[batch_id] = [self.new_job(r, batch_id).job.id for r in body.requests]
            return self.answer(request, self.batch_page(batch_id, 0, 100, advance=False), 202)
        if parts[:2] == ["v1", "batches"] and len(parts) == 3:
            if parts[2] not in self.batches:
                return self.error(request, 404, "no such batch", "NotFound")
            offset = int(request.url.params.get("offset", 0))
            limit = int(request.url.params.get("limit", 100))
            return self.answer(request, self.batch_page(parts[2], offset, limit, advance=True))
        if path == "/v1/robots" and method == "GET":
            return self.answer(request, _RobotList(robots=list(self.robots.values())))
        if path == "/v1/robots" and method == "POST":
            reg = self.body(request, RobotRegister)
            robot = RobotPublic(
                name=reg.name,
                builtin=False,
                dof=2,
                joint_names=["a", "b"],
                lower=[0, 0],
                upper=[1, 1],
                fingertips=reg.fingertips,
                source="user",
            )
            self.robots[reg.name] = robot
            return self.answer(request, robot, 201)
        if parts[:2] == ["v1", "robots"] and len(parts) == 3:
            if parts[2] not in self.robots:
                return self.error(
                    request,
                    404,
                    f"robot.name: unknown hand {parts[2]!r}",
                    "NotFound",
                    detail=[FieldError(field="robot.name", problem="unknown hand")],
                )
            return self.answer(request, self.robots[parts[2]])
        return self.error(request, 404, f"no route {method} {path}", "NotFound")

    def batch_page(self, batch_id: str, offset: int, limit: int, advance: bool) -> BatchPublic:
        ids = self.batches[batch_id]
        page = []
        for i in range(offset, min(offset + limit, len(ids))):
            fake = self.jobs[ids[i]]
            job = self.advance(fake) if advance else fake.job
            page.append(BatchItem(index=i, job_id=job.id, state=job.state, result=job.result, error=job.error))
        counts: dict[JobState, int] = {}
        for job_id in ids:
            state = self.jobs[job_id].job.state
            counts[state] = counts.get(state, 0) + 1
        done = all(self.jobs[j].job.state.terminal for j in ids)
        return BatchPublic(
            id=batch_id,
            total=len(ids),
            counts=counts,
            done=done,
            items=page,
            offset=offset,
            limit=limit,
            created_at=time.time(),
        )

    def sse(self, fake: FakeJob) -> httpx.Response:
        chunks = [": keep-alive\n\n"]
        while True:
            job = self.advance(fake)
            if job.state.terminal:
                chunks.append(f"event: end\ndata: {job.model_dump_json(exclude_none=True)}\n\n")
                break
            slim = job.model_copy(update={"result": None})
            chunks.append(f"event: progress\ndata: {slim.model_dump_json(exclude_none=True)}\n\n")
        return httpx.Response(200, content="".join(chunks).encode(), headers={"content-type": "text/event-stream"})


class _RobotList(WireModel):
    robots: list[RobotPublic]


def json_response(status: int, body: Any, headers: dict[str, str] | None = None) -> httpx.Response:
    return httpx.Response(
        status, content=json.dumps(body).encode(), headers={"content-type": "application/json", **(headers or {})}
    )


@pytest.fixture
def result_factory() -> Callable[..., SynthesisResult]:
    return sample_result


@pytest.fixture
def object_points() -> np.ndarray:
    return sample_object_points()


@pytest.fixture
def fake() -> FakeService:
    return FakeService()


@pytest.fixture
def sleeps() -> list[float]:
    return []


@pytest.fixture
def make_client(fake: FakeService, sleeps: list[float]) -> Iterator[Callable[..., Any]]:
    from clients.sdk import Client

    clients: list[Client] = []

    def make(**kwargs: Any) -> Client:
        kwargs.setdefault("transport", fake.transport())
        kwargs.setdefault("sleep", sleeps.append)
        client = Client("http://testserver", **kwargs)
        clients.append(client)
        return client

    yield make
    for client in clients:
        client.close()
