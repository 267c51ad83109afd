"""One page of a batch as every front end answers it (`GET /v1/batches/{id}`, gRPC `GetBatch`, the MCP tool):
counts by state over all its jobs, and the page's items in request order with their results or errors."""

from __future__ import annotations

import asyncio
import time

from manifoundation.contract import BatchItem, BatchPublic, JobState
from manifoundation.server.queue import JobQueue


async def batch_page(queue: JobQueue, batch_id: str, owner: str | None, offset: int, limit: int) -> BatchPublic:
    """The batch with items ``offset`` .. ``offset + limit - 1``.

    Raises:
        JobNotFound: an unknown batch, or another owner's.
    """
    job_ids = await queue.batch_job_ids(batch_id, owner=owner)
    states = await asyncio.gather(*(queue.get(j, with_result=False) for j in job_ids))
    page = await asyncio.gather(*(queue.get(j) for j in job_ids[offset : offset + limit]))
    counts: dict[JobState, int] = {}
    for job in states:
        counts[job.state] = counts.get(job.state, 0) + 1
    items = [
        BatchItem(index=offset + i, job_id=j.id, state=j.state, result=j.result, error=j.error)
        for i, j in enumerate(page)
    ]
    return BatchPublic(
        id=batch_id, total=len(job_ids), counts=counts, done=all(j.state.terminal for j in states), items=items,
        offset=offset, limit=limit, created_at=min((j.created_at for j in states), default=time.time()),
    )  # fmt: skip
