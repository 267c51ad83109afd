"""The four clients are one surface: the same public methods, with the same parameters, on HTTP and gRPC, sync and
async (the async ones awaited, ``aclose`` for ``close``); their handles too. Calls the gRPC service has no RPC for
raise `NeedsHttp` before sending; the old gRPC names still work for one release, with a `DeprecationWarning`."""

from __future__ import annotations

import asyncio
import contextlib
import inspect
from collections.abc import Callable
from typing import Any

import pytest

from manifoundation.sdk import AsyncBatch, AsyncClient, AsyncJob, Batch, Client, Job, NeedsHttp, Unreachable
from manifoundation.sdk._api import HTTP_ONLY
from manifoundation.sdk.grpc_async_client import AsyncGrpcClient, AsyncGrpcJob
from manifoundation.sdk.grpc_client import GrpcClient, GrpcJob
from tests.api.server import free_port

DEPRECATED: dict[type, set[str]] = {
    GrpcClient: {"get", "cancel", "watch"},
    AsyncGrpcClient: {"get", "cancel", "watch", "close"},
}
"""Old public names kept for one release (each warns); not part of the surface."""
NOT_AWAITED = {"job", "events", "as_completed"}
"""Methods of the async classes that return at once (a handle, an async iterator)."""


def surface(cls: type) -> dict[str, inspect.Signature]:
    """The public methods of ``cls`` and their signatures, the async names read as the sync ones."""
    methods = {
        name: value
        for name, value in inspect.getmembers(cls, callable)
        if not name.startswith("_") and not isinstance(value, type) and name not in DEPRECATED.get(cls, set())
    }
    return {("close" if name == "aclose" else name): inspect.signature(value) for name, value in methods.items()}


def parameters(signature: inspect.Signature) -> list[tuple[str, Any, Any]]:
    """Names, kinds and defaults (not annotations: ``Job`` vs ``AsyncJob``)."""
    return [(p.name, p.kind, p.default) for p in signature.parameters.values()]


@pytest.mark.parametrize(
    ("cls", "reference"),
    [
        (Client, Client),
        (AsyncClient, Client),
        (GrpcClient, Client),
        (AsyncGrpcClient, Client),
        (GrpcJob, Job),
        (AsyncJob, Job),
        (AsyncGrpcJob, Job),
        (AsyncBatch, Batch),
    ],
    ids=lambda c: c.__name__,
)
def test_the_clients_and_their_handles_are_one_surface(cls: type, reference: type) -> None:
    mine, theirs = surface(cls), surface(reference)
    assert sorted(mine) == sorted(theirs), f"{cls.__name__} and {reference.__name__} differ"
    for name, signature in mine.items():
        assert parameters(signature) == parameters(theirs[name]), f"{cls.__name__}.{name}{signature}"
        method = getattr(cls, "aclose" if name == "close" and cls.__name__.startswith("Async") else name)
        awaited = cls.__name__.startswith("Async") and name not in NOT_AWAITED
        assert inspect.iscoroutinefunction(method) == awaited, f"{cls.__name__}.{name} awaited: {awaited}"


def test_the_surface_has_what_the_issue_asks() -> None:
    assert {
        "synthesize", "submit", "submit_plan", "plan", "job", "submit_batch", "batch", "robots", "robot",
        "register_robot", "add_robot", "jobs", "robot_preview", "delete_robot", "health", "ready", "close",
    } <= set(surface(GrpcClient))  # fmt: skip
    assert {"status", "cancel", "wait", "events", "plan_result", "finished"} <= set(surface(GrpcJob))
    assert {"status", "as_completed", "wait", "results"} <= set(surface(Batch)) and "total" in dir(Batch)


@pytest.mark.parametrize("method", sorted(HTTP_ONLY))
def test_calls_without_an_rpc_need_http(method: str) -> None:
    args: dict[str, tuple[Any, ...]] = {"robot_preview": ("h",), "delete_robot": ("h",)}
    with GrpcClient(f"127.0.0.1:{free_port()}", retries=0) as client, pytest.raises(NeedsHttp) as caught:
        getattr(client, method)(*args.get(method, ()))  # nothing listens: raised before sending
    assert caught.value.method == method and "HTTP" in str(caught.value)
    assert isinstance(caught.value, NotImplementedError)

    async def main() -> NeedsHttp:
        async with AsyncGrpcClient(f"127.0.0.1:{free_port()}", retries=0) as client:
            with pytest.raises(NeedsHttp) as raised:
                await getattr(client, method)(*args.get(method, ()))
            return raised.value

    assert asyncio.run(main()).reason == HTTP_ONLY[method]


def test_closing_as_httpx_and_the_old_names_warn() -> None:
    target = f"127.0.0.1:{free_port()}"
    with GrpcClient(target) as client:
        assert isinstance(client, GrpcClient)
    GrpcClient(target).close()

    async def main() -> None:
        async with AsyncGrpcClient(target) as client:
            assert isinstance(client, AsyncGrpcClient)
        await AsyncGrpcClient(target).aclose()
        with pytest.warns(DeprecationWarning, match=r"aclose\(\)"):
            await AsyncGrpcClient(target).close()
        async with AsyncClient("http://127.0.0.1:1") as http:
            assert isinstance(http, AsyncClient)

    asyncio.run(main())


@pytest.mark.parametrize("old", ["get", "cancel", "watch"])
def test_the_old_job_calls_warn(old: str) -> None:
    with GrpcClient(f"127.0.0.1:{free_port()}", retries=0) as client, pytest.warns(DeprecationWarning, match=old):
        call: Callable[[str], Any] = getattr(client, old)
        with contextlib.suppress(Unreachable):  # nothing listens: the warning is what counts
            result = call("some-job")
            if old == "watch":
                next(iter(result))
