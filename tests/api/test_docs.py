"""`/docs` works offline: Swagger UI comes from the installed bundle, not a CDN."""

from __future__ import annotations

import re

from fastapi.testclient import TestClient

from manifoundation.server.api.app import create_app
from manifoundation.server.api.settings import Settings

from .fakes import FakeQueue


def test_docs_page_and_its_assets_are_served_locally() -> None:
    with TestClient(create_app(Settings(), queue=FakeQueue())) as client:  # type: ignore[arg-type]
        page = client.get("/docs")
        assert page.status_code == 200
        sources = re.findall(r'(?:src|href)="([^"]+)"', page.text)
        assert sources and all(s.startswith("/") for s in sources), sources
        for asset in ("/static/swagger/swagger-ui-bundle.js", "/static/swagger/swagger-ui.css"):
            response = client.get(asset)
            assert response.status_code == 200 and len(response.content) > 10_000
        assert client.get("/static/swagger/index.html").status_code == 404
        assert "/v1/synthesize" in client.get("/openapi.json").json()["paths"]
