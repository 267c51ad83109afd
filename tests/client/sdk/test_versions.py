"""The version handshake over HTTP: the real app in process reports its versions, made to report others here."""

from __future__ import annotations

import asyncio
import warnings
from collections.abc import Callable

import httpx
import pytest

from manifoundation.contract.versions import CONTRACT_HEADER, CONTRACT_VERSION, SERVICE_HEADER, parse_version
from manifoundation.sdk import AsyncClient, Client, ContractWarning, IncompatibleService
from manifoundation.server.api.versions import SERVICE_VERSION, Versions
from tests.client.sdk.inprocess import InProcessService
from tests.client.sdk.queues import HAND

MakeClient = Callable[..., Client]
MAJOR, MINOR = parse_version(CONTRACT_VERSION)


def test_every_answer_and_healthz_name_the_versions(make_client: MakeClient, service: InProcessService) -> None:
    client = make_client()
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # the same version: no warning
        health = client.health()
        assert [r.name for r in client.robots()] == [HAND]
    assert health.contract_version == CONTRACT_VERSION and health.version == SERVICE_VERSION
    assert client.versions.service_contract == CONTRACT_VERSION
    with httpx.Client(transport=service.transport()) as http:
        answer = http.get("http://testserver/v1/nothing-here")
    assert answer.status_code == 404  # errors name them too
    assert answer.headers[CONTRACT_HEADER] == CONTRACT_VERSION and answer.headers[SERVICE_HEADER] == SERVICE_VERSION


def test_another_major_version_is_an_error_on_every_call(make_client: MakeClient, service: InProcessService) -> None:
    service.start().state.services.versions = Versions(service="9.0.0", contract=f"{MAJOR + 1}.0")
    client = make_client()
    for _ in range(2):
        with pytest.raises(IncompatibleService) as caught:
            client.robots()
        assert caught.value.service_contract == f"{MAJOR + 1}.0" and caught.value.client_contract == CONTRACT_VERSION
        assert "9.0.0" in str(caught.value) and "manifoundation-client" in str(caught.value)
    assert not client.versions.checked


def test_a_newer_minor_version_warns_once(make_client: MakeClient, service: InProcessService) -> None:
    newer = f"{MAJOR}.{MINOR + 1}"
    service.start().state.services.versions = Versions(contract=newer)
    client = make_client()
    with pytest.warns(ContractWarning, match=newer):
        assert client.robots()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert client.robots()  # checked: later answers are not looked at again
    assert client.versions.service_contract == newer


def test_a_service_older_than_the_handshake_is_not_checked(make_client: MakeClient, service: InProcessService) -> None:
    service.script.append(httpx.Response(200, json={"status": "ok", "backend": "embedded", "version": "0.0.9"}))
    client = make_client()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert client.health().contract_version is None
    assert not client.versions.checked


def test_the_async_client_checks_too(service: InProcessService) -> None:
    service.start().state.services.versions = Versions(contract=f"{MAJOR + 1}.{MINOR}")

    async def call() -> None:
        async with AsyncClient("http://testserver", transport=service.async_transport()) as client:
            await client.robots()

    with pytest.raises(IncompatibleService):
        asyncio.run(call())
