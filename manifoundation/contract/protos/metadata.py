"""The gRPC metadata keys of the contract: what a call carries besides its messages (docs/grpc.md)."""

from __future__ import annotations

AUTHORIZATION = "authorization"
"""``Bearer <key>``: the API key, as HTTP's header."""
JOB_ID = "x-job-id"
"""The job of a `Synthesize` call: in its initial metadata, and in the trailers of a call whose job failed."""
REQUEST_ID = "x-request-id"
"""The caller's request id (kept when sane, as HTTP's header)."""
ERROR = "mani-error-bin"
"""A failed call's error as a ``manifoundation.v1.ErrorBody`` (the HTTP answer's shape)."""
STATUS_DETAILS = "grpc-status-details-bin"
"""A failed call's ``google.rpc.Status`` (``ErrorInfo``, ``BadRequest``, ``RetryInfo``)."""
DOMAIN = "manifoundation.v1"
"""The ``ErrorInfo.domain`` of our errors."""
