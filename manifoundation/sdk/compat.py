"""The SDK's side of the version handshake (docs/compatibility.md), for every transport.

The service names its contract version on every answer (``x-mani-contract-version``: an HTTP header, gRPC
metadata). A client looks at the first answer that has one: another major version raises `IncompatibleService`
(and keeps raising on every later answer, so nothing is read from that service), a newer minor version warns once
with `ContractWarning`, the same or an older minor version passes silently. A service that names no version
(older than the handshake) is not checked.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable

from manifoundation.contract.versions import (
    CONTRACT_HEADER,
    CONTRACT_VERSION,
    SERVICE_HEADER,
    Compatibility,
    compatibility,
)
from manifoundation.sdk.errors import ContractWarning, IncompatibleService

Lookup = Callable[[str], str | None]


class VersionCheck:
    """Compares a service's contract version with this SDK's, once per client.

    Args:
        where: how errors name the service (its URL or target).
        client: the contract version this SDK speaks.
    """

    def __init__(self, where: str, client: str = CONTRACT_VERSION) -> None:
        self.where = where
        self.client = client
        self.service_contract: str | None = None
        self.service_version: str | None = None

    @property
    def checked(self) -> bool:
        """A compatible version has been seen (later answers are not looked at)."""
        return self.service_contract is not None

    def see(self, lookup: Lookup) -> None:
        """Check an answer's headers or metadata (``lookup``: a lower-case name → its value, or None).

        Raises:
            IncompatibleService: the service speaks another major version of the contract.
        """
        if self.checked:
            return
        contract = lookup(CONTRACT_HEADER)
        if contract is None:
            return
        service = lookup(SERVICE_HEADER)
        verdict = compatibility(contract, self.client)
        if verdict is Compatibility.INCOMPATIBLE:
            raise IncompatibleService(contract, self.client, service, self.where)
        if verdict is Compatibility.NEWER_MINOR:
            warnings.warn(
                f"{self.where} speaks contract {contract}, newer than this client's {self.client}: what it added "
                f"is ignored here; upgrade manifoundation-client to use it",
                ContractWarning,
                stacklevel=4,
            )
        self.service_contract, self.service_version = contract, service
