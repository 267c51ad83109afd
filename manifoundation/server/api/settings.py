"""The service's one settings object (pydantic-settings, env prefix ``MANI_``), validated at start-up.

Lists (``MANI_API_KEYS``, ``MANI_OPEN_PATHS``) are comma-separated. Nothing here reads the environment after
`Settings()` is built: the app, the queue and the CLI take this object explicitly.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Annotated, Literal

from pydantic import Field, field_validator
from pydantic_settings import BaseSettings, NoDecode, SettingsConfigDict

from manifoundation.contract import MAX_BATCH_SIZE
from manifoundation.contract.codec import MAX_BODY_BYTES

if TYPE_CHECKING:
    from manifoundation.server.queue.base import RobotLimits
    from manifoundation.server.worker.settings import QueueSettings


class Settings(BaseSettings):
    """Everything the HTTP service can be configured with (env ``MANI_<FIELD>``)."""

    model_config = SettingsConfigDict(env_prefix="MANI_", extra="ignore", validate_default=True)

    # --- where to listen
    host: str = "127.0.0.1"
    port: int = Field(8000, ge=0, le=65535)

    # --- gRPC beside HTTP (`mani serve`; docs/grpc.md): same process, queue, keys and limits
    grpc_port: int = Field(50051, ge=0, le=65535, description="gRPC port of `mani serve`; 0: no gRPC.")
    grpc_host: str | None = Field(None, description="Address gRPC listens on; unset: the HTTP `host`.")
    grpc_max_message_bytes: int = Field(
        MAX_BODY_BYTES, ge=1024 * 1024, le=1024 * 1024 * 1024,
        description="Largest gRPC message in and out (default: the HTTP body limit; 200 000 points fit).",
    )  # fmt: skip
    grpc_stream_window_bytes: int = Field(
        1 << 18, ge=1 << 16, le=1 << 26,
        description="What one gRPC stream reads ahead before its handler asks (its flow-control window; BDP probing"
        " off): the pieces of streams waiting for a large-body slot stay with their clients (100 × 57.6 MB"
        " SubmitBatchStream: API peak 171 MB at 256 KiB, 246 MB at 1 MiB); a stream's rate is at most this per"
        " round trip (2.5 MB/s at 256 KiB and 100 ms).",
    )
    grpc_grace_s: float = Field(5.0, ge=0, le=600, description="Calls in flight get this long at shutdown, s.")
    grpc_health_interval: float = Field(1.0, gt=0, le=60, description="Readiness re-check period of grpc.health.v1.")

    # --- queue: embedded workers (default) or Redis Streams (scale-out; workers run as `mani worker`). Its knobs
    # (MANI_REDIS_URL, MANI_CONCURRENCY, MANI_MAX_QUEUE, MANI_BATCH_SIZE, ...) are
    # `manifoundation.server.worker.settings.QueueSettings`'
    # alone; `queue` holds what the command line set on top of the environment.
    queue: dict[str, object] = Field(
        default_factory=dict, description="Overrides of QueueSettings fields (from the command line)."
    )

    # --- auth and rate limits
    api_keys: Annotated[list[str], NoDecode] = Field(
        default_factory=list, description="Bearer tokens; empty: no auth. Comma-separated in the env."
    )
    admin_keys: Annotated[list[str], NoDecode] = Field(
        default_factory=list, description="Bearer tokens that also read every tenant's jobs (operators)."
    )
    open_paths: Annotated[list[str], NoDecode] = Field(
        default_factory=lambda: ["/healthz", "/readyz", "/metrics"],
        description="Paths served without a key when keys are set (the HTML shells are always open).",
    )
    rate_limit_per_s: float = Field(100.0, ge=0, description="Token refill per key (or client IP); 0: off.")
    rate_limit_burst: int = Field(200, ge=1, description="Token bucket size.")
    auth_failures_per_s: float = Field(1.0, ge=0, description="Wrong-key attempts per client address; 0: off.")
    auth_failures_burst: int = Field(10, ge=1, description="Wrong keys in a row before an address gets 429.")
    forwarded_allow_ips: str | None = Field(
        None,
        description="Proxies whose X-Forwarded-For is believed (uvicorn's forwarded_allow_ips); unset: none, the "
        "client address is the peer's (per-address limits cannot be dodged with a forged header).",
    )

    # --- request handling
    sync_wait_max: float = Field(30.0, gt=0, le=600, description="Cap on how long /v1/synthesize waits.")
    max_body_bytes: int = Field(MAX_BODY_BYTES, ge=1024, le=MAX_BODY_BYTES, description="Request body limit.")
    max_robot_bytes: int = Field(
        24 * 1024 * 1024, ge=1024, description="Body limit of POST /v1/robots (a 16 MiB archive, base64 in JSON)."
    )
    max_robot_store_bytes: int = Field(
        64 * 1024 * 1024, ge=0, description="Descriptions and archives stored per key, bytes (409 beyond; DELETE one)."
    )
    max_robots: int = Field(20, ge=0, le=10_000, description="Registered hands per key (409 beyond; DELETE one).")
    max_batch_size: int = Field(MAX_BATCH_SIZE, ge=1, le=MAX_BATCH_SIZE)
    batch_page_max: int = Field(1000, ge=1, le=MAX_BATCH_SIZE, description="Largest page of GET /v1/batches.")
    robots_cache_s: float = Field(5.0, ge=0, description="How long the hand list is cached for 404 checks.")
    sse_interval: float = Field(0.25, gt=0, le=10, description="Polling interval of the events stream, s.")
    robot_register_timeout: float = Field(
        30.0, gt=0, le=600, description="A registration's deadline, s: the worker still loading it is replaced (504)."
    )
    body_timeout: float = Field(60.0, gt=0, le=3600, description="A request body must arrive within this, s (408).")
    body_idle_timeout: float = Field(10.0, gt=0, le=600, description="Longest pause within a body, s (408).")
    header_timeout: float = Field(
        10.0, gt=0, le=600, description="A request's line and headers must arrive within this, s (408, closed)."
    )
    parse_offload_bytes: int = Field(
        1024 * 1024, ge=0, description="Bodies larger than this are decoded in a worker process, off the event loop."
    )
    large_body_slots: int = Field(2, ge=1, le=64, description="Large bodies read and decoded at once (the rest wait).")

    # --- MCP tools at /mcp (manifoundation/server/api/mcp; `mani mcp` over stdio): objects uploaded by agents, per key
    mcp: bool = Field(True, description="Serve the MCP tools at /mcp (streamable HTTP).")
    object_ttl_s: float = Field(3600.0, gt=0, le=7 * 86400, description="An uploaded object lives this long after "
                                "its last use, s.")  # fmt: skip
    max_objects: int = Field(32, ge=1, le=10_000, description="Uploaded objects per key (409 beyond).")
    max_object_store_bytes: int = Field(
        64 * 1024 * 1024, ge=1024, description="Bytes of uploaded objects' arrays per key (409 beyond)."
    )
    mcp_stream_max_s: float = Field(
        300.0, gt=0, le=86400, description="A `GET /mcp` event stream is closed after this long, s (the client "
        "reconnects if it still listens); a stream costs a connection and a file descriptor."
    )
    mcp_max_streams: int = Field(8, ge=1, le=10_000, description="Open `GET /mcp` event streams per key (429 beyond).")
    mcp_max_body_bytes: int = Field(
        MAX_BODY_BYTES, ge=1024, le=MAX_BODY_BYTES, description="Body limit of `POST /mcp` (413 beyond). An "
        "`upload_object` call over `MANI_PARSE_OFFLOAD_BYTES` is decoded in a body process, as `/v1` bodies are; "
        "other calls: 1 MiB."
    )

    # --- observability
    log_level: str = Field("INFO", pattern=r"^(DEBUG|INFO|WARNING|ERROR|CRITICAL)$")
    log_format: Literal["json", "text"] = "json"
    dashboard_sample_s: float = Field(2.0, gt=0, le=60, description="Dashboard time-series sampling period.")
    dashboard_history: int = Field(900, ge=10, le=100_000, description="Samples kept for the dashboard.")

    @field_validator("api_keys", "admin_keys", "open_paths", mode="before")
    @classmethod
    def _split_csv(cls, value: object) -> object:
        if isinstance(value, str):
            return [part.strip() for part in value.split(",") if part.strip()]
        return value

    @field_validator("api_keys", "admin_keys")
    @classmethod
    def _keys_are_long_enough(cls, value: list[str]) -> list[str]:
        short = [k for k in value if len(k) < 8]
        if short:
            raise ValueError(f"{len(short)} API key(s) shorter than 8 characters")
        return value

    @field_validator("log_level", mode="before")
    @classmethod
    def _upper(cls, value: object) -> object:
        return value.upper() if isinstance(value, str) else value

    @property
    def auth_enabled(self) -> bool:
        """Whether `/v1` routes need a bearer key (then every key is its own tenant)."""
        return bool(self.api_keys or self.admin_keys)

    @property
    def all_keys(self) -> list[str]:
        """Every accepted key: the tenants' and the operators'."""
        return [*self.api_keys, *(k for k in self.admin_keys if k not in self.api_keys)]

    def robot_limits(self) -> RobotLimits:
        """What one key may register (``max_robots``, ``max_robot_store_bytes``), for every front end."""
        from manifoundation.server.queue.base import RobotLimits

        return RobotLimits(max_robots=self.max_robots, max_bytes=self.max_robot_store_bytes)

    def queue_settings(self) -> QueueSettings:
        """The queue's settings: env ``MANI_*`` for its knobs, the command line's ``queue`` overrides on top."""
        from manifoundation.server.worker.settings import QueueSettings

        return QueueSettings(**self.queue)  # type: ignore[arg-type]
