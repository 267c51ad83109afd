"""The front ends share one typed `AppServices` (issue 61: `app.state` was an untyped bag reached by HTTP, gRPC and
MCP). Read statically: no module of the API reaches into ``app.state`` for anything but ``services``; and at run
time: the app's services are the ones its routes, gRPC and MCP were given."""

from __future__ import annotations

import re
from pathlib import Path

from fastapi.testclient import TestClient

from manifoundation.server.api.app import create_app
from manifoundation.server.api.services import AppServices, services_of
from manifoundation.server.api.settings import Settings

from .fakes import FakeQueue

API = Path(__file__).resolve().parents[2] / "manifoundation" / "server" / "api"
BAG = re.compile(r"\bapp\.state\.(?!services\b)[a-z_]+")


def test_no_module_of_the_api_reads_the_untyped_state() -> None:
    offenders = [
        f"{path.relative_to(API)}:{n}: {line.strip()}"
        for path in sorted(API.rglob("*.py"))
        for n, line in enumerate(path.read_text().splitlines(), 1)
        if BAG.search(line)
    ]
    assert not offenders, "\n".join(offenders)


def test_the_lifespan_fills_the_apps_services() -> None:
    app = create_app(Settings(), queue=FakeQueue())  # type: ignore[arg-type]
    services = services_of(app)
    assert isinstance(services, AppServices) and services.queue is None and services.robots is None
    with TestClient(app) as client:
        assert client.get("/healthz").status_code == 200
        assert services.queue is not None and services.robots is not None and services.mcp is not None
    assert services.shutting_down
