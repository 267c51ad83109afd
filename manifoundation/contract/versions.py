"""The contract's version, and the rule a client and a service compare it by (docs/compatibility.md).

``MAJOR.MINOR``: a minor version only adds (optional request fields, answer fields, routes, RPCs, error types,
values of an enumeration that only requests carry); a major version changes or removes anything, or adds a value to
an enumeration the service answers with (job state, stage). The major version is the ``/v1`` of the routes and the
``manifoundation.v1`` of the proto. The service reports its version on every
answer (``x-mani-contract-version``: an HTTP header, gRPC metadata) and in ``GET /healthz``.
"""

from __future__ import annotations

import enum
import re

CONTRACT_VERSION = "1.8"
"""This contract's version: bump the minor version for an addition, the major one for a break."""
CONTRACT_HEADER = "x-mani-contract-version"
"""The HTTP header and the gRPC metadata key that carry the service's contract version."""
SERVICE_HEADER = "x-mani-service-version"
"""The HTTP header and the gRPC metadata key that carry the service's own (distribution) version."""

_VERSION = re.compile(r"^\s*(\d+)\.(\d+)\s*$")


class Compatibility(enum.Enum):
    """How a service's contract relates to a client's."""

    SAME = "same"
    NEWER_MINOR = "newer_minor"  # the service adds what this client does not know: answers may carry more
    OLDER_MINOR = "older_minor"  # the client knows more than the service: a newer field may be refused by name
    INCOMPATIBLE = "incompatible"  # another major version, or no version that can be read


def parse_version(text: str) -> tuple[int, int]:
    """``"1.2"`` → ``(1, 2)``.

    Raises:
        ValueError: not ``MAJOR.MINOR``.
    """
    match = _VERSION.match(text)
    if match is None:
        raise ValueError(f"not a MAJOR.MINOR contract version: {text!r}")
    return int(match.group(1)), int(match.group(2))


def compatibility(service: str, client: str = CONTRACT_VERSION) -> Compatibility:
    """The relation of a service's contract version to a client's (both ``MAJOR.MINOR``).

    Args:
        service: the version the service reports.
        client: the version the client was built with (this package's, by default).
    """
    try:
        (s_major, s_minor), (c_major, c_minor) = parse_version(service), parse_version(client)
    except ValueError:
        return Compatibility.INCOMPATIBLE
    if s_major != c_major:
        return Compatibility.INCOMPATIBLE
    if s_minor > c_minor:
        return Compatibility.NEWER_MINOR
    if s_minor < c_minor:
        return Compatibility.OLDER_MINOR
    return Compatibility.SAME
