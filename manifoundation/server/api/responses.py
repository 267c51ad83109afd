"""OpenAPI documentation of the error answers (every one is an `ErrorBody`)."""

from __future__ import annotations

from typing import Any

from manifoundation.contract import ErrorBody

_ERROR_TEXT = {
    400: "Malformed body or parameter",
    401: "Missing or unknown API key",
    404: "Unknown job, batch or hand",
    408: "The body did not arrive in time",
    413: "Body over the size limit",
    415: "Body neither JSON nor msgpack",
    422: "Validation failed: `detail` names each field and problem",
    429: "Rate limited or queue full (see Retry-After)",
    503: "Shutting down or queue unavailable (see Retry-After)",
}


def errors(*codes: int) -> dict[int | str, dict[str, Any]]:
    """``responses=`` entries for the given error codes (all of them by default)."""
    return {code: {"model": ErrorBody, "description": _ERROR_TEXT[code]} for code in codes or _ERROR_TEXT}


ERRORS = errors()
READ_ERRORS = errors(400, 401, 404, 429, 503)


