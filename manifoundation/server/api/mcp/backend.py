"""Where the MCP tools send their work: the service's own submission path, or the SDK over HTTP.

Both answer the same small protocol (`Backend`) with the contract's models, so the tools have one implementation
and validation has one (the contract's, then the service's own checks):

- `ServiceBackend` (the server mounted at ``/mcp`` in `mani serve`): the HTTP routes' `Submitter` (admission,
  hand check, submission on the caller's behalf, the viewer's scene, the metrics) and the queue's tenant-scoped
  reads, for the `Caller` the request's API key is;
- `ClientBackend` (``mani mcp`` over stdio): `manifoundation.sdk.AsyncClient` against a running service, with the key
  given to the command (the service then does exactly what it does for any SDK call).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Protocol

from manifoundation.contract import BatchPublic, ErrorBody, JobPublic, PlanRequest, RobotPublic, SynthesisRequest
from manifoundation.sdk import AsyncBatch, AsyncClient, ManiError, RequestError
from manifoundation.sdk.errors import TimeoutError as SdkTimeout
from manifoundation.server.api.batch_pages import batch_page
from manifoundation.server.api.errors import from_exception
from manifoundation.server.api.security import Caller
from manifoundation.server.api.submission import Submitter, running_queue
from manifoundation.server.api.waiting import wait_for_job

if TYPE_CHECKING:
    from manifoundation.server.api.services import AppServices


class Backend(Protocol):
    """What the tools need from the service, for one caller."""

    async def robots(self) -> list[RobotPublic]:
        """The hands the caller may use."""
        ...

    async def submit(self, request: SynthesisRequest) -> str:
        """Queue a synthesis; its job id."""
        ...

    async def submit_plan(self, request: PlanRequest) -> str:
        """Queue a plan; its job id."""
        ...

    async def submit_batch(self, requests: list[SynthesisRequest]) -> str:
        """Queue a batch, all or none; its id."""
        ...

    async def job(self, job_id: str, wait: float = 0.0) -> JobPublic:
        """The caller's job, once it ended or after ``wait`` seconds, whichever is first."""
        ...

    async def batch(self, batch_id: str, offset: int, limit: int) -> BatchPublic:
        """One page of the caller's batch."""
        ...

    def view_url(self, job_id: str) -> str | None:
        """Where a person can look at the job in a browser (None: unknown)."""
        ...


def error_body(exc: Exception) -> ErrorBody:
    """The contract's error for anything a backend raises (the service's translation, or the SDK's error)."""
    if isinstance(exc, RequestError):
        return exc.body
    if isinstance(exc, ManiError):
        return ErrorBody(error=str(exc), type="Unavailable")
    return from_exception(exc).body()


class ServiceBackend:
    """In the API process: the routes' objects (the app's `AppServices`), for ``caller``."""

    def __init__(self, services: AppServices, caller: Caller, request_id: str, base_url: str | None = None) -> None:
        self.services, self.caller, self.request_id, self.base_url = services, caller, request_id, base_url

    @property
    def queue(self) -> Any:
        return running_queue(self.services)

    def _submitter(self) -> Submitter:
        s = self.services
        return Submitter(self.queue, s.catalog(), s.metrics, s.settings, s.scenes, self.request_id, self.caller,
                         transport="mcp")  # fmt: skip

    async def robots(self) -> list[RobotPublic]:
        robots: list[RobotPublic] = await self.services.catalog().all(self.caller.tenant, fresh=True)
        return robots

    async def submit(self, request: SynthesisRequest) -> str:
        submitter = self._submitter()
        await submitter.admit()
        return await submitter.submit(request, "async", None)

    async def submit_plan(self, request: PlanRequest) -> str:
        submitter = self._submitter()
        await submitter.admit()
        return await submitter.submit(request, "plan", None)

    async def submit_batch(self, requests: list[SynthesisRequest]) -> str:
        from manifoundation.contract import BatchCreate

        submitter = self._submitter()
        await submitter.admit(len(requests))
        return await submitter.submit_batch(BatchCreate(requests=requests))

    async def job(self, job_id: str, wait: float = 0.0) -> JobPublic:
        queue, owner = self.queue, self.caller.scope
        job: JobPublic = await queue.get(job_id, owner=owner)  # NotFound for another tenant's job
        if not job.state.terminal and wait > 0:
            job = await wait_for_job(self.services, queue, job_id, wait, fetch_with="with get_job")
        self.services.metrics.observe_job(job)
        return job

    async def batch(self, batch_id: str, offset: int, limit: int) -> BatchPublic:
        return await batch_page(self.queue, batch_id, self.caller.scope, offset, limit)

    def view_url(self, job_id: str) -> str | None:
        return None if self.base_url is None else f"{self.base_url.rstrip('/')}/view/{job_id}"


class ClientBackend:
    """Over HTTP with the SDK (``mani mcp``): one `AsyncClient` for the command's key."""

    def __init__(self, client: AsyncClient) -> None:
        self.client = client

    async def robots(self) -> list[RobotPublic]:
        return await self.client.robots()

    async def submit(self, request: SynthesisRequest) -> str:
        return (await self.client.submit(request)).id

    async def submit_plan(self, request: PlanRequest) -> str:
        return (await self.client.submit_plan(request)).id

    async def submit_batch(self, requests: list[SynthesisRequest]) -> str:
        return (await self.client.submit_batch(requests)).id

    async def job(self, job_id: str, wait: float = 0.0) -> JobPublic:
        handle = self.client.job(job_id)
        if wait <= 0:
            return await handle.status()
        try:
            return await handle.finished(wait)
        except SdkTimeout:
            return await handle.status()

    async def batch(self, batch_id: str, offset: int, limit: int) -> BatchPublic:
        return await AsyncBatch(self.client, batch_id).status(offset=offset, limit=limit)

    def view_url(self, job_id: str) -> str | None:
        return f"{self.client.base_url.rstrip('/')}/view/{job_id}"
