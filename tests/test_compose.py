"""docker-compose.yml and Dockerfile are consistent with the code (no Docker engine runs here)."""

from __future__ import annotations

import re
from importlib.metadata import entry_points
from pathlib import Path

import yaml

ROOT = Path(__file__).resolve().parents[1]
COMPOSE = yaml.safe_load((ROOT / "docker-compose.yml").read_text())
MANI_COMMANDS = {ep.name for ep in entry_points(group="mani.commands")}


def test_services_present() -> None:
    assert set(COMPOSE["services"]) == {"redis", "api", "worker"}


def test_commands_are_real_mani_subcommands() -> None:
    for name in ("api", "worker"):
        command = COMPOSE["services"][name]["command"]
        assert command[0] == "mani" and command[1] in MANI_COMMANDS, f"{name}: {command}"


def test_api_and_worker_share_image_and_redis() -> None:
    api, worker = COMPOSE["services"]["api"], COMPOSE["services"]["worker"]
    assert api["image"] == worker["image"]
    assert "build" in api and "build" not in worker and "ports" not in worker, "worker must be scalable"
    url = api["environment"]["MANI_REDIS_URL"]
    assert worker["environment"]["MANI_REDIS_URL"] == url
    assert url.split("//", 1)[1].split(":", 1)[0] == "redis"
    for service in (api, worker):
        assert url in service["command"]
        assert service["depends_on"]["redis"]["condition"] == "service_healthy"


def test_healthchecks_use_real_routes_and_ports() -> None:
    api = COMPOSE["services"]["api"]
    port = api["command"][api["command"].index("--port") + 1]
    assert api["ports"] == [f"{port}:{port}"]
    assert f"127.0.0.1:{port}/healthz" in " ".join(api["healthcheck"]["test"])
    assert "ping" in COMPOSE["services"]["redis"]["healthcheck"]["test"]


def test_dockerfile_installs_pinned_torch_and_exposes_api_port() -> None:
    dockerfile = (ROOT / "Dockerfile").read_text()
    assert "torch==2.13.0" in dockerfile
    command = COMPOSE["services"]["api"]["command"]
    port = command[command.index("--port") + 1]
    assert re.search(rf"^EXPOSE {port}$", dockerfile, re.M)
    assert "COPY manifoundation ./manifoundation" in dockerfile
    assert "research" not in dockerfile  # the image holds the product only
