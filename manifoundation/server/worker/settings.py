"""One settings object for the queue and the worker processes (pydantic-settings, env prefix ``MANI_``).

Every field can be set from the environment: ``MANI_REDIS_URL``, ``MANI_QUEUE_PREFIX``, ``MANI_CONCURRENCY``,
``MANI_BATCH_SIZE``, ``MANI_MAX_WAIT_MS``, ``MANI_MAX_QUEUE``, ``MANI_RESULT_TTL``, ``MANI_MAX_RESULTS``,
``MANI_MAX_RESULT_BYTES``, ``MANI_REDIS_TIMEOUT``, ``MANI_VISIBILITY_TIMEOUT``, ``MANI_HEARTBEAT_INTERVAL``,
``MANI_MAX_DELIVERIES``, ``MANI_PIPELINE``, ``MANI_PIPELINE_OPTIONS`` (JSON), ``MANI_WEIGHTS_DIR``,
``MANI_START_TIMEOUT``, ``MANI_LOG_LEVEL``.
Validated at start-up: a bad value fails fast.
"""

from __future__ import annotations

from typing import Any

from pydantic import Field, field_validator
from pydantic_settings import BaseSettings, SettingsConfigDict


class QueueSettings(BaseSettings):
    """Queue backend and worker pool configuration (shared by `create_queue` and `mani worker`)."""

    model_config = SettingsConfigDict(env_prefix="MANI_", extra="ignore")

    # backend
    redis_url: str | None = Field(None, description="Redis URL; unset: the embedded (in-process) backend.")
    queue_prefix: str = Field("mani:", min_length=1, max_length=64, description="Namespace of every Redis key.")
    max_queue: int = Field(10_000, ge=1, description="Pending jobs at most; submit raises QueueFull beyond.")
    result_ttl: float = Field(3600.0, gt=0, description="Seconds a result is kept after the job ends.")
    record_ttl: float = Field(7 * 86400.0, gt=0, description="Seconds a job's record (state, no result) is kept.")
    max_results: int = Field(10_000, ge=1, description="Embedded: finished jobs kept in memory at most.")
    max_result_bytes: int = Field(
        32 * 2**20, ge=0, description="Embedded: bytes of finished jobs' results kept in memory at most."
    )
    redis_timeout: float = Field(
        2.0, gt=0, le=60, description="Seconds a Redis connect or command may take before the call fails (503)."
    )
    # workers
    concurrency: int = Field(
        2, ge=0, le=64, description="Worker processes: spawned by `mani serve` (embedded) or by `mani worker`."
    )
    batch_size: int = Field(4, ge=1, le=64, description="Jobs a worker takes at once (network micro-batch).")
    max_wait_ms: float = Field(0.0, ge=0, le=10_000, description="How long a worker waits to fill a batch.")
    visibility_timeout: float = Field(
        60.0, gt=0, description="A job silent this long is re-delivered (a dead worker's: after heartbeat_timeout)."
    )
    heartbeat_interval: float = Field(2.0, gt=0, description="Seconds between worker heartbeats.")
    max_deliveries: int = Field(3, ge=1, le=100, description="Deliveries before a job goes to dead letters.")
    pipeline: str = Field(
        "manifoundation.server.worker.models_pipeline:ModelsPipeline", description="module:attr of the Pipeline."
    )
    pipeline_options: dict[str, Any] = Field(default_factory=dict, description="Keyword arguments of it.")
    weights_dir: str | None = Field(None, description="Checkpoint directory (default: manifoundation/core/weights).")
    start_timeout: float = Field(60.0, ge=0, description="Embedded start(): wait this long for workers' hello.")
    log_level: str = Field("INFO")

    @field_validator("pipeline")
    @classmethod
    def _import_path(cls, value: str) -> str:
        module, _, attr = value.partition(":")
        if not module or not attr:
            raise ValueError("pipeline: expected 'module:attribute'")
        return value

    @property
    def heartbeat_timeout(self) -> float:
        """A worker silent this long is considered gone."""
        return max(3 * self.heartbeat_interval, 1.0)
