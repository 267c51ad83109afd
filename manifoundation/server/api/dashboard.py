"""What the operator's dashboard shows: a sampled time series of the queue plus a snapshot of now.

The sampler runs in the app's lifespan (one sample every ``dashboard_sample_s``); the page polls
`GET /dashboard/data` and draws it (service-local models below: purely a service concern, not wire contract).
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import time
from collections import OrderedDict, deque

from manifoundation.contract import DashboardPublic, JobKind, JobPublic, JobState, Sample
from manifoundation.server.queue import JobQueue

log = logging.getLogger("manifoundation.server.api.dashboard")
RECENT_JOBS = 200
"""The window of the latencies and the verified-grasp rate: the most recently submitted jobs."""
_FINISHED = (JobState.SUCCEEDED, JobState.FAILED)


def percentile(values: list[float], q: float) -> float | None:
    """The ``q``-quantile (0..1) by linear interpolation; None for no values."""
    if not values:
        return None
    ordered = sorted(values)
    pos = (len(ordered) - 1) * q
    low = int(pos)
    high = min(low + 1, len(ordered) - 1)
    return ordered[low] + (ordered[high] - ordered[low]) * (pos - low)


class History:
    """A ring of `Sample`s, filled by `run` (a lifespan task)."""

    def __init__(self, queue: JobQueue, period: float, size: int) -> None:
        self.queue = queue
        self.period = period
        self.samples: deque[Sample] = deque(maxlen=size)
        self._verified: OrderedDict[str, bool] = OrderedDict()  # job id → its best proposal is verified (final)

    async def sample(self) -> None:
        """Take one sample now."""
        stats = await self.queue.stats()
        self.samples.append(
            Sample(
                t=time.time(),
                depth=stats.depth,
                running=stats.running,
                by_state=stats.by_state,
                completed_total=stats.completed_total,
                failed_total=stats.failed_total,
            )
        )

    async def run(self) -> None:
        """Sample forever (cancelled at shutdown); a failing queue only skips samples."""
        while True:
            with contextlib.suppress(Exception):
                await self.sample()
            await asyncio.sleep(self.period)

    def throughput(self, window: float = 60.0) -> float:
        """Finished (succeeded + failed) jobs per second over the last ``window`` seconds."""
        if len(self.samples) < 2:
            return 0.0
        last = self.samples[-1]
        first = next((s for s in self.samples if s.t >= last.t - window), self.samples[0])
        dt = last.t - first.t
        done = (last.completed_total + last.failed_total) - (first.completed_total + first.failed_total)
        return max(0.0, done / dt) if dt > 0 else 0.0

    async def verified(self, jobs: list[JobPublic]) -> tuple[int, int]:
        """(verified, finished) over the synthesis jobs of ``jobs`` that finished: a succeeded job counts as
        verified when its best proposal (any, as `SynthesisResult.best` picks a verified one first) passed
        verification, a failed one never. Each job's result is read once (``jobs`` come without results), then
        remembered."""
        finished = [j for j in jobs if j.kind is JobKind.SYNTHESIS and j.state in _FINISHED]
        verified = 0
        for job in finished:
            if job.state is JobState.FAILED:
                continue
            known = self._verified.get(job.id)
            if known is None:
                try:
                    result = (await self.queue.get(job.id)).result
                except Exception:  # the result expired meanwhile: not counted as either
                    continue
                known = result is not None and any(p.quality.success for p in result.proposals)
                self._verified[job.id] = known
                while len(self._verified) > 4 * RECENT_JOBS:
                    self._verified.popitem(last=False)
            verified += known
        return verified, len(finished)

    async def snapshot(self, recent: int = 25, owner: str | None = None) -> DashboardPublic:
        """Everything the page shows; with ``owner`` (a tenant's key) only that tenant's jobs and dead letters,
        and no worker's current job (the queue-wide counts and the series stay: they name no job)."""
        now = time.time()
        try:
            stats = await self.queue.stats()
            jobs = await self.queue.list_recent(limit=RECENT_JOBS, owner=owner)
            workers = await self.queue.workers()
            dead = await self.queue.dead_letters(limit=20)
            if owner is not None:
                mine = {j.id for j in jobs}
                dead = [d for d in dead if d.job_id in mine]
                workers = [w.model_copy(update={"current_job": None}) for w in workers]
            verified, finished = await self.verified(jobs)
        except Exception as exc:
            log.warning("dashboard: queue did not answer: %s", exc)
            return DashboardPublic(now=now, backend=self.queue.backend, queue_up=False, series=list(self.samples))
        latencies = [j.finished_at - j.created_at for j in jobs if j.state.terminal and j.finished_at is not None]
        return DashboardPublic(
            now=now,
            backend=self.queue.backend,
            queue_up=True,
            stats=stats,
            throughput_per_s=self.throughput(),
            latency_p50=percentile(latencies, 0.5),
            latency_p99=percentile(latencies, 0.99),
            finished_jobs=finished,
            verified_grasps=verified,
            verified_rate=verified / finished if finished else None,
            series=list(self.samples),
            workers=workers,
            recent=jobs[:recent],
            dead_letters=dead,
        )
