"""Rate-limit gaps closed: wrong keys are limited per address, and a forged X-Forwarded-For does not give a
client a fresh per-address bucket (`mani serve`'s uvicorn configuration)."""

from __future__ import annotations

import threading
import time

import httpx
import uvicorn
from fastapi.testclient import TestClient

from manifoundation.server.api.app import create_app
from manifoundation.server.api.cli import uvicorn_config
from manifoundation.server.api.settings import Settings

from .fakes import FakeQueue
from .server import free_port

KEY = "secret-key-1234"


def test_wrong_keys_are_rate_limited_per_address() -> None:
    settings = Settings(api_keys=[KEY], auth_failures_burst=5, auth_failures_per_s=0.5)
    with TestClient(create_app(settings, queue=FakeQueue())) as client:
        guesses = [client.get("/v1/jobs", headers={"Authorization": f"Bearer guess-{i:04d}"}) for i in range(8)]
        assert [g.status_code for g in guesses] == [401] * 5 + [429] * 3
        assert int(guesses[-1].headers["retry-after"]) >= 1
        assert client.get("/healthz").status_code == 200  # open paths are not affected


def test_forged_forwarded_for_does_not_dodge_the_per_address_limit() -> None:
    settings = Settings(rate_limit_per_s=0.1, rate_limit_burst=3, host="127.0.0.1", port=free_port())
    server = uvicorn.Server(uvicorn_config(create_app(settings, queue=FakeQueue()), settings))
    thread = threading.Thread(target=server.run, daemon=True)
    thread.start()
    try:
        while not server.started:
            time.sleep(0.02)
        base = f"http://127.0.0.1:{settings.port}"
        codes = [httpx.get(f"{base}/v1/jobs", headers={"X-Forwarded-For": f"10.0.0.{i}"}).status_code for i in range(5)]
        assert codes == [200, 200, 200, 429, 429]
    finally:
        server.should_exit = True
        thread.join(30)
