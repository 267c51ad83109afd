"""The versions the service reports: its own and its wire contract's (docs/compatibility.md).

Every HTTP answer carries them as headers and every gRPC call as metadata (``x-mani-contract-version``,
``x-mani-service-version``); ``GET /healthz`` has them in its body. Clients compare the contract version with
their own on their first answer. They are read from the app's `AppServices.versions` on each answer, so a test can
make an app report another version (``services_of(app).versions = Versions(contract="2.0")``).
"""

from __future__ import annotations

from dataclasses import dataclass
from importlib.metadata import version as package_version

from manifoundation.contract.versions import CONTRACT_HEADER, CONTRACT_VERSION, SERVICE_HEADER

SERVICE_VERSION = package_version("manifoundation")
"""The installed distribution's version (pyproject.toml is its one source)."""


@dataclass(frozen=True)
class Versions:
    """What the service says it is: ``service`` its distribution's version, ``contract`` the wire contract's."""

    service: str = SERVICE_VERSION
    contract: str = CONTRACT_VERSION

    def metadata(self) -> tuple[tuple[str, str], ...]:
        """The versions as (lower-case) header / metadata pairs."""
        return (CONTRACT_HEADER, self.contract), (SERVICE_HEADER, self.service)

    def raw_headers(self) -> list[tuple[bytes, bytes]]:
        """The versions as ASGI response headers."""
        return [(name.encode(), value.encode("latin-1")) for name, value in self.metadata()]



