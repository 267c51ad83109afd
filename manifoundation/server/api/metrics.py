"""Prometheus metrics of one app (its own registry, so several apps can live in one process).

Request metrics are observed by the middleware; queue figures (depth, jobs by state, workers, dead letters)
are read from the queue when `/metrics` is scraped; stage durations are observed once per finished job that
the service sees (recent jobs at scrape time, or a job a client fetched).
"""

from __future__ import annotations

from collections import OrderedDict
from collections.abc import Iterable

from prometheus_client import CollectorRegistry, Counter, Gauge, Histogram, disable_created_metrics, generate_latest
from prometheus_client.core import CounterMetricFamily, Metric
from prometheus_client.registry import Collector

from manifoundation.contract import JobPublic, JobState, QueueStats
from manifoundation.server.queue import JobQueue

LATENCY_BUCKETS = (0.005, 0.01, 0.025, 0.05, 0.1, 0.25, 0.5, 1, 2.5, 5, 10, 30, 60, 120)
STAGE_BUCKETS = (0.001, 0.005, 0.01, 0.025, 0.05, 0.1, 0.25, 0.5, 1, 2.5, 5, 10, 30)
BATCH_BUCKETS = (1, 2, 5, 10, 25, 50, 100, 250, 500, 1000)
SEEN_JOBS = 10_000


class _QueueTotals(Collector):
    """The queue's own monotonic totals, exposed as counters (the queue counts; we only copy)."""

    def __init__(self) -> None:
        self.completed = 0
        self.failed = 0

    def collect(self) -> Iterable[Metric]:
        yield CounterMetricFamily("mani_jobs_completed", "Jobs finished successfully (queue).", value=self.completed)
        yield CounterMetricFamily("mani_jobs_failed", "Jobs that failed (queue).", value=self.failed)


class Metrics:
    """The app's collectors."""

    def __init__(self) -> None:
        disable_created_metrics()  # no `_created` series: they double the exposition for nothing
        self.registry = CollectorRegistry(auto_describe=True)
        r = self.registry
        self.requests = Counter(
            "mani_requests", "HTTP requests by route and status.", ["method", "route", "status"], registry=r
        )
        self.request_duration = Histogram(
            "mani_request_duration_seconds",
            "HTTP request latency (until the response starts).",
            ["method", "route"],
            buckets=LATENCY_BUCKETS,
            registry=r,
        )
        self.in_flight = Gauge("mani_requests_in_flight", "HTTP requests being served.", registry=r)
        self.jobs_submitted = Counter("mani_jobs_submitted", "Jobs enqueued by this API process.", ["kind"], registry=r)
        self.batch_size = Histogram("mani_batch_size", "Requests per batch.", buckets=BATCH_BUCKETS, registry=r)
        self.job_duration = Histogram(
            "mani_job_duration_seconds",
            "Job latency from submission to its terminal state.",
            ["state"],
            buckets=LATENCY_BUCKETS,
            registry=r,
        )
        self.stage_duration = Histogram(
            "mani_stage_duration_seconds", "Pipeline stage durations.", ["stage"], buckets=STAGE_BUCKETS, registry=r
        )
        self.queue_depth = Gauge("mani_queue_depth", "Jobs waiting to be picked up.", registry=r)
        self.jobs_running = Gauge("mani_jobs_running", "Jobs being computed.", registry=r)
        self.jobs_by_state = Gauge("mani_jobs", "Known jobs by state.", ["state"], registry=r)
        self.queue_totals = _QueueTotals()
        r.register(self.queue_totals)
        self.workers = Gauge("mani_workers", "Live workers.", registry=r)
        self.workers_ready = Gauge("mani_workers_model_loaded", "Live workers with their model loaded.", registry=r)
        self.dead_letters = Gauge("mani_dead_letters", "Jobs in the dead-letter list.", registry=r)
        self.queue_up = Gauge("mani_queue_up", "1 when the queue answered the last scrape.", registry=r)
        self._seen: OrderedDict[str, None] = OrderedDict()

    def observe_job(self, job: JobPublic) -> None:
        """Record a terminal job's duration and stage timings, once per job id."""
        if not job.state.terminal or job.id in self._seen:
            return
        self._seen[job.id] = None
        while len(self._seen) > SEEN_JOBS:
            self._seen.popitem(last=False)
        if job.finished_at is not None:
            self.job_duration.labels(state=job.state.value).observe(max(0.0, job.finished_at - job.created_at))
        timings = dict(job.timings)
        answer = job.result or job.plan
        if answer is not None:
            timings = {**answer.timings, **timings}
        for stage, seconds in timings.items():
            if seconds >= 0:
                self.stage_duration.labels(stage=stage).observe(seconds)

    def set_stats(self, stats: QueueStats) -> None:
        """Copy the queue's figures into the gauges."""
        self.queue_depth.set(stats.depth)
        self.jobs_running.set(stats.running)
        for state in JobState:
            self.jobs_by_state.labels(state=state.value).set(stats.by_state.get(state, 0))
        self.queue_totals.completed = stats.completed_total
        self.queue_totals.failed = stats.failed_total
        self.dead_letters.set(stats.dead_letters)

    async def refresh(self, queue: JobQueue) -> None:
        """Read the queue's figures (called on scrape); a queue that does not answer sets ``mani_queue_up 0``."""
        try:
            self.set_stats(await queue.stats())
            workers = await queue.workers()
            self.workers.set(len(workers))
            self.workers_ready.set(sum(1 for w in workers if w.model_loaded))
            self.observe_jobs(await queue.list_recent(limit=200))
            self.queue_up.set(1)
        except Exception:
            self.queue_up.set(0)

    def observe_jobs(self, jobs: Iterable[JobPublic]) -> None:
        """`observe_job` for each job."""
        for job in jobs:
            self.observe_job(job)

    def render(self) -> bytes:
        """The Prometheus text exposition."""
        return generate_latest(self.registry)
