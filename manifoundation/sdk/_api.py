"""The one surface of the synchronous clients: `Client` (HTTP) and `GrpcClient` (gRPC) are `SyncAPI` over a
`Transport`, as httpx's ``Client`` is its logic over a transport.

`SyncAPI` and its handles (`Job`, `Batch`) hold every decision a call makes: building and checking the request
(`make_request`, `make_plan`, `robot_registration`, `hand_registration`), waiting on a job or a batch (polling, or
following the service's stream where the transport has one), turning a finished job into its result or
`JobFailed`. A `Transport` only sends one call and converts its answer to the contract's model. A call the
gRPC service has no RPC for raises `NeedsHttp` (the defaults of `Transport`; `HTTP_ONLY` says why for each).
`manifoundation.sdk._async_api` is the same for the asyncio clients.

Why one module: the surface, its two handles and the transport interface they drive are one unit, read together;
splitting them would only add imports between the parts.
"""

from __future__ import annotations

import os
import time
from abc import ABC, abstractmethod
from collections.abc import Callable, Iterator
from typing import Any, ClassVar, Self

from manifoundation.contract import (
    BatchItem,
    BatchPublic,
    ContactsIn,
    HealthPublic,
    JobCreated,
    JobPublic,
    PlanRequest,
    PlanResult,
    ReadyPublic,
    RobotPreview,
    RobotPublic,
    RobotRegister,
    SynthesisRequest,
    SynthesisResult,
)
from manifoundation.sdk.compat import VersionCheck
from manifoundation.sdk.errors import NeedsHttp, NotFound, TimeoutError
from manifoundation.sdk.hands import hand_registration
from manifoundation.sdk.objects import ObjectLike
from manifoundation.sdk.plans import PoseLike, make_plan
from manifoundation.sdk.requests import RobotLike, make_request, robot_registration
from manifoundation.sdk.retry import poll_delays
from manifoundation.sdk.tasks import TaskLike
from manifoundation.sdk.tracking import (
    PLAN,
    RESULT,
    Answer,
    BatchTracker,
    item_result,
    job_result,
    plan_result,
    settled,
)

PLAN_GRACE = 60.0
"""How much longer than a plan's ``options.timeout`` `plan` waits by default, seconds."""

HTTP_ONLY: dict[str, str] = {
    "jobs": "the gRPC service has no RPC that lists jobs",
    "robot_preview": "the gRPC service has no RPC for a hand's preview",
    "delete_robot": "the gRPC service has no RPC that removes a hand",
    "health": "grpc.health.v1 answers SERVING or not, without the backend and version of HealthPublic",
    "ready": "grpc.health.v1 answers SERVING or not, without the queue, workers and model of ReadyPublic",
}
"""The client calls that only HTTP serves, and why (the message of their `NeedsHttp` over gRPC)."""


def plan_wait(request: PlanRequest, wait: float | None) -> float:
    """How long `plan` waits for its job: ``wait``, else the plan's ``options.timeout`` and `PLAN_GRACE`."""
    return request.options.timeout + PLAN_GRACE if wait is None else wait


def needs_http(method: str) -> NeedsHttp:
    """The error of a call only HTTP serves."""
    return NeedsHttp(method, HTTP_ONLY[method])


def find_robot(robots: list[RobotPublic], name: str) -> RobotPublic:
    """``name`` among ``robots`` (a ``ListRobots`` answer), without its preview data, as ``GET /v1/robots/{name}``.

    Raises:
        NotFound: no hand of that name for this key (the service's ``UnknownHand``).
    """
    for robot in robots:
        if robot.name == name:
            return robot.model_copy(update={"preview": None})
    raise NotFound(f"unknown hand {name!r}", type="UnknownHand")


class Transport(ABC):
    """How a synchronous client sends: one method per call, each one request (or one stream) and the conversion
    of its answer; no waiting, polling or argument handling.

    Attributes:
        streams: jobs and batches are followed on the service's streams (``WatchJob``, ``WatchBatch``) rather
            than polled.
        versions: the version handshake, fed by every answer.
        poll_interval: the largest pause between two polls, seconds.
    """

    streams: ClassVar[bool] = False
    versions: VersionCheck
    poll_interval: float = 1.0

    def sleep(self, seconds: float) -> None:
        """Wait between polls (tests may record instead)."""
        time.sleep(seconds)

    @abstractmethod
    def close(self) -> None:
        """Release the connection pool or channel."""

    @abstractmethod
    def synthesize(self, request: SynthesisRequest) -> SynthesisResult | JobCreated:
        """Submit and wait on the service's side; a `JobCreated` when the service answered before the job ended."""

    @abstractmethod
    def submit(self, request: SynthesisRequest) -> str:
        """Queue a synthesis; its job id."""

    @abstractmethod
    def submit_plan(self, request: PlanRequest) -> str:
        """Queue a plan; its job id."""

    @abstractmethod
    def job(self, job_id: str, with_result: bool = True) -> JobPublic:
        """The job now."""

    @abstractmethod
    def cancel(self, job_id: str) -> JobPublic:
        """Ask the service to cancel the job."""

    @abstractmethod
    def events(self, job_id: str, timeout: float | None) -> Iterator[JobPublic]:
        """The job on every change, ending with its final state."""

    @abstractmethod
    def submit_batch(self, requests: list[SynthesisRequest]) -> str:
        """Queue many syntheses; the batch id."""

    @abstractmethod
    def batch(self, batch_id: str, offset: int, limit: int) -> BatchPublic:
        """One page of a batch."""

    def batch_items(self, batch_id: str, timeout: float | None) -> Iterator[BatchItem]:
        """Each item of a batch as it ends (a transport that `streams`)."""
        raise NotImplementedError(f"{type(self).__name__} does not stream batches")

    @abstractmethod
    def robots(self) -> list[RobotPublic]:
        """The hands this key may use."""

    def robot(self, name: str) -> RobotPublic:
        """One hand (default: found in `robots`)."""
        return find_robot(self.robots(), name)

    @abstractmethod
    def register_robot(self, body: RobotRegister) -> RobotPublic:
        """Register a hand."""

    def jobs(self, limit: int) -> list[JobPublic]:
        """The most recent jobs."""
        raise needs_http("jobs")

    def robot_preview(self, name: str) -> RobotPreview:
        """A registered hand's preview data."""
        raise needs_http("robot_preview")

    def delete_robot(self, name: str) -> None:
        """Remove a hand."""
        raise needs_http("delete_robot")

    def health(self) -> HealthPublic:
        """Liveness."""
        raise needs_http("health")

    def ready(self) -> ReadyPublic:
        """Readiness."""
        raise needs_http("ready")


class SyncAPI:
    """The calls of a synchronous client, over any `Transport` (`Client`: HTTP, `GrpcClient`: gRPC).

    A client is closed by `close` or by leaving its ``with`` block.
    """

    _job_type: ClassVar[type[Job]]

    def __init__(self, transport: Transport) -> None:
        self._transport = transport

    @property
    def versions(self) -> VersionCheck:
        """The contract version handshake with the service (`manifoundation.sdk.compat`)."""
        return self._transport.versions

    def close(self) -> None:
        """Close the connection pool (HTTP) or channel (gRPC)."""
        self._transport.close()

    def __enter__(self) -> Self:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # ---- synthesis ------------------------------------------------------------------------------------------

    def synthesize(
        self,
        object: ObjectLike | SynthesisRequest,
        task: TaskLike = "force_closure",
        robot: RobotLike = "leap",
        *,
        contacts: ContactsIn | dict[str, Any] | None = None,
        **options: Any,
    ) -> SynthesisResult:
        """Synthesise contacts, forces and a hand pose, and wait for the answer.

        Args:
            object: an `ObjectIn`, (N, 3)/(N, 6) array, trimesh mesh, file path, dict — or a whole
                `SynthesisRequest` (then ``task``, ``robot``, ``contacts`` and ``options`` are ignored).
            task: a task model, a dict with ``kind``, or ``"force_closure"``.
            robot: a hand name (``"leap"``, ``"allegro"``, a registered name), a `RobotIn` or a dict.
            contacts: given contacts (method ``"contacts"``).
            **options: `SynthesisOptions` fields; ``timeout`` (default 30 s) is the whole wait (over gRPC also the
                call's deadline, which the service makes the job's: the job ends *expired* when it passes).

        Returns:
            The result; its arrays are numpy arrays and ``result.best`` is the best proposal.

        Raises:
            ValidationError: invalid input (checked before sending, and by the service).
            TimeoutError: no result within ``timeout`` (``exc.job_id`` names the job).
            JobFailed: the job failed, was cancelled or expired.
        """
        request = make_request(object, task, robot, contacts=contacts, **options)
        deadline = time.monotonic() + request.options.timeout
        answer = self._transport.synthesize(request)
        if isinstance(answer, JobCreated):
            return self.job(answer.id).wait(max(0.0, deadline - time.monotonic()))
        return answer

    def submit(
        self,
        object: ObjectLike | SynthesisRequest,
        task: TaskLike = "force_closure",
        robot: RobotLike = "leap",
        *,
        contacts: ContactsIn | dict[str, Any] | None = None,
        **options: Any,
    ) -> Job:
        """Queue a synthesis and return at once with its `Job` (same arguments as `synthesize`)."""
        request = make_request(object, task, robot, contacts=contacts, **options)
        return self.job(self._transport.submit(request))

    def submit_plan(
        self,
        object: ObjectLike | PlanRequest,
        start: PoseLike | None = None,
        waypoints: list[PoseLike] | None = None,
        robot: RobotLike = "allegro",
        **fields: Any,
    ) -> Job:
        """Queue a manipulation plan and return at once with its `Job` (``job.plan_result()`` waits for it).
        Arguments as `manifoundation.sdk.make_plan` (or one whole `PlanRequest`)."""
        request = make_plan(object, start, waypoints or [], robot, **fields)
        return self.job(self._transport.submit_plan(request))

    def plan(
        self,
        object: ObjectLike | PlanRequest,
        start: PoseLike | None = None,
        waypoints: list[PoseLike] | None = None,
        robot: RobotLike = "allegro",
        *,
        wait: float | None = None,
        **fields: Any,
    ) -> PlanResult:
        """Plan a manipulation and wait for it: the dense collision-free trajectory, the repaired waypoints and a
        verified contact answer per step.

        Args:
            object, start, waypoints, robot, **fields: as `manifoundation.sdk.make_plan` (or one whole `PlanRequest`).
            wait: seconds to wait (default: the plan's ``options.timeout`` plus `PLAN_GRACE`, a minute).

        Raises:
            ValidationError: invalid input; JobFailed: e.g. ``InfeasibleWaypoint`` / ``NoPathFound`` (its
                ``error.detail`` names the waypoint); TimeoutError: not finished within ``wait``.
        """
        request = make_plan(object, start, waypoints or [], robot, **fields)
        return self.submit_plan(request).plan_result(plan_wait(request, wait))

    def job(self, job_id: str) -> Job:
        """A handle on an existing job (submitted over either transport)."""
        return self._job_type(self, job_id)

    def jobs(self, limit: int = 50) -> list[JobPublic]:
        """The most recent jobs, newest first (without results). HTTP only (`NeedsHttp` over gRPC)."""
        return self._transport.jobs(limit)

    def submit_batch(self, requests: list[SynthesisRequest]) -> Batch:
        """Queue many requests in one call, all or none (up to `MAX_BATCH_SIZE`); build them with `make_request`."""
        requests = list(requests)
        return Batch(self, self._transport.submit_batch(requests), total=len(requests))

    def batch(self, batch_id: str) -> Batch:
        """A handle on an existing batch."""
        return Batch(self, batch_id)

    # ---- robots and health ----------------------------------------------------------------------------------

    def robots(self) -> list[RobotPublic]:
        """The built-in hands and the ones this key registered."""
        return self._transport.robots()

    def robot(self, name: str) -> RobotPublic:
        """One hand: DoF, joints and limits, fingertips (`NotFound` for an unknown name)."""
        return self._transport.robot(name)

    def register_robot(
        self,
        urdf: str | bytes | os.PathLike[str],
        fingertips: list[str],
        *,
        name: str | None = None,
        tip_offsets: Any = None,
    ) -> RobotPublic:
        """Register a custom hand from a URDF (text or file); every worker can use it by ``name`` afterwards."""
        return self._transport.register_robot(robot_registration(urdf, fingertips, name=name, tip_offsets=tip_offsets))

    def add_robot(
        self,
        source: str | bytes | os.PathLike[str],
        *,
        palm: str | None = None,
        fingertips: list[str] | None = None,
        name: str | None = None,
        tip_offsets: Any = None,
        description: str | None = None,
        rest: dict[str, float] | None = None,
        approach_axis: Any = None,
    ) -> RobotPublic:
        """Register a hand from an archive (zip/tar of a URDF or MJCF and its meshes), a folder, or a description
        file (see `manifoundation.sdk.hands`); ``palm`` cuts it from a whole robot. The answer reports DoF, fingertips,
        spheres, pad areas, couplings, what was ignored, and ``view_url``."""
        body = hand_registration(
            source, palm=palm, fingertips=fingertips, name=name, tip_offsets=tip_offsets, description=description,
            rest=rest, approach_axis=approach_axis,
        )  # fmt: skip
        return self._transport.register_robot(body)

    def robot_preview(self, name: str) -> RobotPreview:
        """A registered hand at rest (palm frame): coarse meshes, collision spheres, pad samples, fingertips.
        HTTP only (`NeedsHttp` over gRPC)."""
        return self._transport.robot_preview(name)

    def delete_robot(self, name: str) -> None:
        """Remove a hand this key registered (jobs naming it afterwards get 404). HTTP only."""
        self._transport.delete_robot(name)

    def health(self) -> HealthPublic:
        """``GET /healthz``: the service is alive (raises when not). HTTP only (over gRPC: grpc.health.v1)."""
        return self._transport.health()

    def ready(self) -> ReadyPublic:
        """``GET /readyz``: model loaded, workers alive, queue reachable (``ready`` False when not). HTTP only."""
        return self._transport.ready()


class Job:
    """A queued synthesis or plan: poll it, wait for it, follow its progress, cancel it."""

    def __init__(self, client: SyncAPI, job_id: str) -> None:
        self.client = client
        self.id = job_id

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.id!r})"

    def status(self) -> JobPublic:
        """The job now: state, stage and progress, timings, and its result or error when finished."""
        return self.client._transport.job(self.id)

    def cancel(self) -> JobPublic:
        """Ask the service to cancel the job (no effect when it already finished)."""
        return self.client._transport.cancel(self.id)

    def events(self, timeout: float | None = None) -> Iterator[JobPublic]:
        """The job's progress as it happens (HTTP: Server-Sent Events; gRPC: ``WatchJob``), ending with its final
        state.

        Args:
            timeout: HTTP: longest silence between two events; gRPC: the whole stream; seconds (None: no limit).
        """
        return self.client._transport.events(self.id, timeout)

    def wait(self, timeout: float | None = None) -> SynthesisResult:
        """Wait until the job finishes and return its result.

        Raises:
            TimeoutError: still running after ``timeout`` seconds (None: wait for ever).
            JobFailed: it failed, was cancelled or expired.
        """
        return job_result(self._until_done(timeout, RESULT))

    def plan_result(self, timeout: float | None = None) -> PlanResult:
        """Wait until a plan job finishes and return its plan (raises as `wait`)."""
        return plan_result(self._until_done(timeout, PLAN))

    def finished(self, timeout: float | None = None) -> JobPublic:
        """Wait until the job has ended (whichever way); the job then. Raises `TimeoutError` after ``timeout``."""
        return self._until_done(timeout, None)

    def _until_done(self, timeout: float | None, answer: Answer | None) -> JobPublic:
        """Follow the job's stream where the transport has one (read once more when it ended early or without
        ``answer``), else poll it."""
        if self.client._transport.streams:
            last: JobPublic | None = None
            for job in self.events(timeout):
                last = job
            done = settled(last, answer)
            return self.status() if done is None else done
        deadline = None if timeout is None else time.monotonic() + timeout
        for delay in poll_delays(cap=self.client._transport.poll_interval):
            job = self.status()
            if job.state.terminal:
                return job
            if deadline is not None:
                left = deadline - time.monotonic()
                if left <= 0:
                    raise TimeoutError(f"job {self.id} still {job.state.value} after {timeout:g} s", job_id=self.id)
                delay = min(delay, left)
            self.client._transport.sleep(delay)
        raise AssertionError("unreachable")


class Batch:
    """Many queued syntheses: counts, results in request order, or items as they finish."""

    def __init__(self, client: SyncAPI, batch_id: str, total: int | None = None, page_size: int = 100) -> None:
        self.client = client
        self.id = batch_id
        self.page_size = page_size
        self._total = total

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.id!r})"

    @property
    def total(self) -> int:
        """Number of requests in the batch."""
        if self._total is None:
            self._total = self.status(limit=1).total
        return self._total

    def status(self, offset: int = 0, limit: int = 100) -> BatchPublic:
        """Counts by state and one page of items (with results of finished items)."""
        return self.client._transport.batch(self.id, offset, limit)

    def as_completed(self, timeout: float | None = None) -> Iterator[BatchItem]:
        """Each item (``index``, ``state``, ``result`` or ``error``) as soon as it finishes (gRPC: ``WatchBatch``;
        HTTP: pages polled).

        Raises:
            TimeoutError: not all items finished within ``timeout`` seconds.
        """
        if self.client._transport.streams:
            done = 0
            try:
                for item in self.client._transport.batch_items(self.id, timeout):
                    done += 1
                    yield item
            except TimeoutError as exc:
                raise TimeoutError(f"batch {self.id}: {done}/{self.total} done after {timeout:g} s") from exc
            return
        yield from self._polled(timeout)

    def _polled(self, timeout: float | None) -> Iterator[BatchItem]:
        tracker = BatchTracker(self.id, self.total, self.page_size)
        deadline = None if timeout is None else time.monotonic() + timeout
        delays = poll_delays(cap=self.client._transport.poll_interval)
        while not tracker.done:
            for n, offset in enumerate(tracker.pending_pages()):
                if n > 0 and not tracker.worth_more_pages():
                    break
                yield from tracker.update(self.status(offset, self.page_size))
            for item in tracker.missing_results():
                yield tracker.fill(item.index, self.client.job(item.job_id).status())
            if tracker.done:
                return
            delay = next(delays)
            if deadline is not None:
                left = deadline - time.monotonic()
                if left <= 0:
                    done = len(tracker.reported)
                    raise TimeoutError(f"batch {self.id}: {done}/{tracker.total} done after {timeout:g} s")
                delay = min(delay, left)
            self.client._transport.sleep(delay)

    def wait(
        self, timeout: float | None = None, progress: Callable[[BatchItem], object] | None = None
    ) -> list[BatchItem]:
        """Wait for every item; return them in request order (each with its ``result`` or ``error``).

        Args:
            timeout: seconds (None: wait for ever).
            progress: called with each item as it finishes (e.g. to advance a progress bar).
        """
        items: dict[int, BatchItem] = {}
        for item in self.as_completed(timeout):
            items[item.index] = item
            if progress is not None:
                progress(item)
        return [items[i] for i in range(self.total)]

    def results(self, timeout: float | None = None) -> list[SynthesisResult]:
        """Every result in request order.

        Raises:
            JobFailed: for the first item that did not succeed.
        """
        return [item_result(item) for item in self.wait(timeout)]


SyncAPI._job_type = Job
