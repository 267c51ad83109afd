"""Following jobs and batches without I/O: batch bookkeeping, results or `JobFailed`, progress events."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from operator import attrgetter

import pydantic

from manifoundation.contract import BatchItem, BatchPublic, JobPublic, JobState, PlanResult, SynthesisResult
from manifoundation.contract.common import ANSWER_CONTEXT
from manifoundation.sdk.errors import JobFailed, ServerError

# SSE event types that carry a job (``progress`` while it runs, ``end`` with the final job).
JOB_EVENT_TYPES = frozenset({"message", "progress", "end"})


@dataclass
class BatchTracker:
    """Which items of a batch are finished, fed one `BatchPublic` page at a time (no I/O).

    The client fetches `pages_to_fetch()` each round, feeds every page to `update`, and reports the items it
    returns; `missing_results()` lists succeeded items whose page carried no result (the client then reads
    the job itself).
    """

    batch_id: str
    total: int
    page_size: int = 100
    items: list[BatchItem | None] = field(init=False)
    reported: set[int] = field(default_factory=set)
    server_terminal: int = 0

    def __post_init__(self) -> None:
        self.items = [None] * self.total

    @property
    def done(self) -> bool:
        """Whether every item was reported."""
        return len(self.reported) == self.total

    def pending_pages(self) -> list[int]:
        """Offsets of the pages that hold an item not yet reported, lowest first."""
        pending = (i for i in range(self.total) if i not in self.reported)
        return sorted({(i // self.page_size) * self.page_size for i in pending})

    def worth_more_pages(self) -> bool:
        """After the first page of a round: whether the other pages can hold news (counts say so)."""
        return self.server_terminal > len(self.reported)

    def update(self, page: BatchPublic) -> list[BatchItem]:
        """Record a page; return its items that just finished (with a result or an error)."""
        self.server_terminal = sum(n for state, n in page.counts.items() if JobState(state).terminal)
        fresh = []
        for item in page.items:
            if not 0 <= item.index < self.total:
                continue
            self.items[item.index] = item
            if item.index in self.reported or not item.state.terminal:
                continue
            if item.state is JobState.SUCCEEDED and item.result is None:
                continue  # its result comes from the job itself: see missing_results
            self.reported.add(item.index)
            fresh.append(item)
        return fresh

    def missing_results(self) -> list[BatchItem]:
        """Succeeded items whose result was not in their page."""
        return [
            item
            for item in self.items
            if item is not None
            and item.index not in self.reported
            and item.state is JobState.SUCCEEDED
            and item.result is None
        ]

    def fill(self, index: int, job: JobPublic) -> BatchItem:
        """Complete an item from its job (read separately) and mark it reported."""
        item = BatchItem(index=index, job_id=job.id, state=job.state, result=job.result, error=job.error)
        self.items[index] = item
        self.reported.add(index)
        return item


def job_result(job: JobPublic) -> SynthesisResult:
    """The result of a finished job, or `JobFailed` when it has none."""
    if job.state is JobState.SUCCEEDED and job.result is not None:
        return job.result
    raise JobFailed.from_job(job)


def plan_result(job: JobPublic) -> PlanResult:
    """The plan of a finished plan job, or `JobFailed` when it has none."""
    if job.state is JobState.SUCCEEDED and job.plan is not None:
        return job.plan
    raise JobFailed.from_job(job)


def item_result(item: BatchItem) -> SynthesisResult:
    """The result of a finished batch item, or `JobFailed` when it has none."""
    if item.state is JobState.SUCCEEDED and item.result is not None:
        return item.result
    raise JobFailed.of(item.job_id, item.state, item.error)


def parse_event(data: str) -> JobPublic:
    """One SSE ``data`` payload: a `JobPublic` in JSON."""
    try:
        return JobPublic.model_validate_json(data, context=ANSWER_CONTEXT)
    except pydantic.ValidationError as exc:
        raise ServerError(f"unreadable job event: {exc}", type="ProtocolError") from exc


Answer = Callable[[JobPublic], object]
"""What a succeeded job must carry to be complete (its result, its plan)."""
RESULT: Answer = attrgetter("result")
PLAN: Answer = attrgetter("plan")


def settled(last: JobPublic | None, answer: Answer | None) -> JobPublic | None:
    """The last job a stream gave when it is final and complete; None: read the job once more (the stream
    ended early, or its final job came without ``answer``)."""
    if last is None or not last.state.terminal:
        return None
    if last.state is JobState.SUCCEEDED and answer is not None and answer(last) is None:
        return None
    return last
