"""Fixtures shared by the service's test packages."""

from __future__ import annotations

from collections.abc import Iterator

import pytest

from .science import Science, science_service


@pytest.fixture(scope="package", params=["embedded", pytest.param("redis", marks=pytest.mark.slow)])
def science(request: pytest.FixtureRequest) -> Iterator[Science]:
    """The service with the science behind it (`tests.api.science`), shared by the plan and MCP tests."""
    with science_service(request) as service:
        yield service
