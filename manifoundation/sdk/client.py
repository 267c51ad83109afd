"""`Client`: the synchronous SDK. Every decision lives in `BaseClient`; this module only sends and sleeps.

Why one module: it mirrors `AsyncClient` method for method (the httpx pattern); keeping each client in one file
keeps the two surfaces side by side and reviewable.
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable, Iterator
from typing import Any, TypeVar

import httpx

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
    SynthesisRequest,
    SynthesisResult,
)
from manifoundation.sdk._core import BaseClient, Call
from manifoundation.sdk.errors import TimeoutError
from manifoundation.sdk.hands import hand_registration
from manifoundation.sdk.objects import ObjectLike
from manifoundation.sdk.plans import PoseLike, make_plan
from manifoundation.sdk.requests import RobotLike, make_request, robot_registration
from manifoundation.sdk.retry import poll_delays
from manifoundation.sdk.sse import SSEDecoder
from manifoundation.sdk.tasks import TaskLike
from manifoundation.sdk.tracking import JOB_EVENT_TYPES, BatchTracker, item_result, job_result, parse_event, plan_result

T = TypeVar("T")


class Client(BaseClient):
    """Talk to a ManiFoundation service from synchronous code.

    Example::

        from manifoundation.sdk import Client, object_from_file

        with Client("http://127.0.0.1:8000") as client:
            result = client.synthesize(object_from_file("examples/data/box.npz"), "force_closure", "leap")
            print(result.best.quality)

    Args:
        base_url, api_key, timeout, retries, encoding, headers, poll_interval: see `BaseClient`.
        transport: an ``httpx.BaseTransport`` to send through (tests: the app in process).
        sleep: how to wait between retries and polls (tests may pass a no-op).
    """

    def __init__(
        self,
        base_url: str | None = None,
        api_key: str | None = None,
        *,
        transport: httpx.BaseTransport | None = None,
        sleep: Callable[[float], None] = time.sleep,
        **kwargs: Any,
    ) -> None:
        super().__init__(base_url, api_key, **kwargs)
        self._http = httpx.Client(transport=transport, timeout=self.timeout)
        self._sleep = sleep

    def close(self) -> None:
        """Close the connection pool."""
        self._http.close()

    def __enter__(self) -> Client:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # ---- sending --------------------------------------------------------------------------------------------

    def send(self, request: httpx.Request, *, stream: bool = False, retry: bool = True) -> httpx.Response:
        """Send with retries (429/503 and connection errors, backoff + jitter, Retry-After honoured)."""
        attempt = 0 if retry else self.retry_policy.max_retries
        while True:
            try:
                response = self._http.send(request, stream=stream)
            except httpx.TransportError as exc:
                delay = self.retry_delay(attempt, request, exc=exc)
                if delay is None:
                    raise self.transport_error(request, exc) from exc
            else:
                delay = self.retry_delay(attempt, request, response=response)
                if delay is None:
                    if stream and not response.is_success:
                        response.read()
                    return response
                response.close()
            self._sleep(delay)
            attempt += 1

    def _run(self, call: Call[T]) -> T:
        return call.parse(self.send(call.request, retry=call.retry))

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
            **options: `SynthesisOptions` fields; ``timeout`` (default 30 s) is the whole wait.

        Returns:
            The result; its arrays are numpy arrays and ``result.best`` is the best proposal.

        Raises:
            ValidationError: invalid input (checked before sending, and by the service).
            TimeoutError: no result within ``timeout`` (``exc.job_id`` names the job, which may still finish).
            JobFailed: the job failed, was cancelled or expired.
        """
        request = make_request(object, task, robot, contacts=contacts, **options)
        deadline = time.monotonic() + request.options.timeout
        answer = self._run(self._call_synthesize(request))
        if isinstance(answer, JobCreated):
            return Job(self, answer.id).wait(max(0.0, deadline - time.monotonic()))
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
        return Job(self, self._run(self._call_submit(request)).id)

    def submit_plan(
        self,
        object: ObjectLike | PlanRequest,
        start: PoseLike | None = None,
        waypoints: list[PoseLike] | None = None,
        robot: RobotLike = "allegro",
        **fields: Any,
    ) -> Job:
        """Queue a manipulation plan (``POST /v1/plans``) and return at once with its `Job` (``job.plan_result()``
        waits for it). Arguments as `manifoundation.sdk.make_plan` (or one whole `PlanRequest`)."""
        request = make_plan(object, start, waypoints or [], robot, **fields)
        return Job(self, self._run(self._call_submit_plan(request)).id)

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
            wait: seconds to wait (default: the plan's ``options.timeout`` plus a minute in the queue).

        Raises:
            ValidationError: invalid input; JobFailed: e.g. ``InfeasibleWaypoint`` / ``NoPathFound`` (its
                ``error.detail`` names the waypoint); TimeoutError: not finished within ``wait``.
        """
        request = make_plan(object, start, waypoints or [], robot, **fields)
        job = Job(self, self._run(self._call_submit_plan(request)).id)
        return job.plan_result(request.options.timeout + 60.0 if wait is None else wait)

    def job(self, job_id: str) -> Job:
        """A handle on an existing job."""
        return Job(self, job_id)

    def jobs(self, limit: int = 50) -> list[JobPublic]:
        """The most recent jobs, newest first (without results)."""
        return self._run(self._call_jobs(limit))

    def submit_batch(self, requests: list[SynthesisRequest]) -> Batch:
        """Queue many requests in one call (up to `MAX_BATCH_SIZE`); build them with `make_request`."""
        return Batch(self, self._run(self._call_submit_batch(list(requests))), total=len(requests))

    def batch(self, batch_id: str) -> Batch:
        """A handle on an existing batch."""
        return Batch(self, batch_id)

    # ---- robots and health ----------------------------------------------------------------------------------

    def robots(self) -> list[RobotPublic]:
        """The built-in and registered hands."""
        return self._run(self._call_robots())

    def robot(self, name: str) -> RobotPublic:
        """One hand: DoF, joints and limits, fingertips."""
        return self._run(self._call_robot(name))

    def register_robot(
        self,
        urdf: str | bytes | os.PathLike[str],
        fingertips: list[str],
        *,
        name: str | None = None,
        tip_offsets: Any = None,
    ) -> RobotPublic:
        """Register a custom hand from a URDF (text or file); every worker can use it by ``name`` afterwards."""
        body = robot_registration(urdf, fingertips, name=name, tip_offsets=tip_offsets)
        return self._run(self._call_register_robot(body))

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
        return self._run(self._call_register_robot(body))

    def robot_preview(self, name: str) -> RobotPreview:
        """A registered hand at rest (palm frame): coarse meshes, collision spheres, pad samples, fingertips."""
        return self._run(self._call_robot_preview(name))

    def delete_robot(self, name: str) -> None:
        """Remove a hand this key registered (jobs naming it afterwards get 404)."""
        self._run(self._call_delete_robot(name))

    def health(self) -> HealthPublic:
        """``GET /healthz``: the service is alive (raises when not)."""
        return self._run(self._call_health())

    def ready(self) -> ReadyPublic:
        """``GET /readyz``: model loaded, workers alive, queue reachable (``ready`` False when not)."""
        return self._run(self._call_ready())


class Job:
    """A queued synthesis: poll it, wait for it, follow its progress, cancel it."""

    def __init__(self, client: Client, job_id: str) -> None:
        self.client = client
        self.id = job_id

    def __repr__(self) -> str:
        return f"Job({self.id!r})"

    def status(self) -> JobPublic:
        """The job now: state, stage and progress, timings, and its result or error when finished."""
        return self.client._run(self.client._call_job(self.id))

    def cancel(self) -> JobPublic:
        """Ask the service to cancel the job (no effect when it already finished)."""
        return self.client._run(self.client._call_cancel(self.id))

    def wait(self, timeout: float | None = None) -> SynthesisResult:
        """Wait until the job finishes and return its result.

        Raises:
            TimeoutError: still running after ``timeout`` seconds (None: wait for ever).
            JobFailed: it failed, was cancelled or expired.
        """
        return job_result(self.finished(timeout))

    def plan_result(self, timeout: float | None = None) -> PlanResult:
        """Wait until a plan job finishes and return its plan (raises as `wait`)."""
        return plan_result(self.finished(timeout))

    def finished(self, timeout: float | None = None) -> JobPublic:
        """Poll until the job has ended (whichever way); the job then. Raises `TimeoutError` after ``timeout``."""
        deadline = None if timeout is None else time.monotonic() + timeout
        for delay in poll_delays(cap=self.client.poll_interval):
            job = self.status()
            if job.state.terminal:
                return job
            if deadline is not None:
                left = deadline - time.monotonic()
                if left <= 0:
                    raise TimeoutError(f"job {self.id} still {job.state.value} after {timeout:g} s", job_id=self.id)
                delay = min(delay, left)
            self.client._sleep(delay)
        raise AssertionError("unreachable")

    def events(self, timeout: float | None = None) -> Iterator[JobPublic]:
        """The job's progress as it happens (Server-Sent Events), ending with its final state.

        Args:
            timeout: longest silence between two events, seconds (None: no limit).
        """
        request = self.client.build_request(
            "GET", f"/v1/jobs/{self.id}/events", accept="text/event-stream", read_timeout=timeout
        )
        response = self.client.send(request, stream=True)
        try:
            self.client.raise_for_status(response)
            decoder = SSEDecoder()
            for line in response.iter_lines():
                event = decoder.decode(line)
                if event is None or not event.data or event.event not in JOB_EVENT_TYPES:
                    continue
                job = parse_event(event.data)
                yield job
                if job.state.terminal:
                    return
        except httpx.TimeoutException as exc:
            raise TimeoutError(f"no progress from job {self.id} in {timeout} s", job_id=self.id) from exc
        finally:
            response.close()


class Batch:
    """Many queued syntheses: counts, results in request order, or items as they finish."""

    def __init__(self, client: Client, batch_id: str, total: int | None = None, page_size: int = 100) -> None:
        self.client = client
        self.id = batch_id
        self.page_size = page_size
        self._total = total

    def __repr__(self) -> str:
        return f"Batch({self.id!r})"

    @property
    def total(self) -> int:
        """Number of requests in the batch."""
        if self._total is None:
            self._total = self.status(limit=1).total
        return self._total

    def status(self, offset: int = 0, limit: int = 100) -> BatchPublic:
        """Counts by state and one page of items (with results of finished items)."""
        return self.client._run(self.client._call_batch(self.id, offset, limit))

    def as_completed(self, timeout: float | None = None) -> Iterator[BatchItem]:
        """Each item (``index``, ``state``, ``result`` or ``error``) as soon as it finishes.

        Raises:
            TimeoutError: not all items finished within ``timeout`` seconds.
        """
        tracker = BatchTracker(self.id, self.total, self.page_size)
        deadline = None if timeout is None else time.monotonic() + timeout
        delays = poll_delays(cap=self.client.poll_interval)
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
            self.client._sleep(delay)

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
