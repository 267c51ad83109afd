"""The operator's dashboard (`GET /`) and the result viewer (`GET /view/{id}`, `GET /v1/jobs/{id}/view`),
offline: plotly's bundle is served from the installed package (`/static/plotly.min.js`), never from a CDN.

The HTML shells `/` and `/view/{id}` carry no data and are open (the same page whatever the id: nothing about a job
leaks); the data they fetch (`/dashboard/data`, `/v1/jobs/{id}/scene`) needs a key when keys are set, and the
pages read it from the URL fragment (``#key=...``, never sent to a server). `/v1/jobs/{id}/view` is the same page
under `/v1`: with keys set it needs the key and answers 404 for another tenant's job, like every `/v1` route.
"""

from __future__ import annotations

import importlib.util
from pathlib import Path

from fastapi import APIRouter, Request
from fastapi.openapi.docs import get_swagger_ui_html
from starlette.responses import FileResponse, HTMLResponse, Response

from manifoundation.contract import DashboardPublic, ScenePublic
from manifoundation.server.api.deps import Authorized, CallerDep, HistoryDep, QueueDep, SettingsDep
from manifoundation.server.api.errors import NotFound
from manifoundation.server.api.negotiation import respond
from manifoundation.server.api.responses import READ_ERRORS
from manifoundation.server.api.services import services_of

STATIC = Path(__file__).resolve().parent.parent / "static"
SWAGGER_FILES = frozenset({"swagger-ui-bundle.js", "swagger-ui.css", "favicon-32x32.png"})

pages = APIRouter(include_in_schema=False)
data = APIRouter(tags=["dashboard"], dependencies=[Authorized])


def plotly_bundle() -> Path:
    """The plotly.min.js shipped inside the plotly wheel (found without importing plotly)."""
    spec = importlib.util.find_spec("plotly")
    for root in (spec.submodule_search_locations or []) if spec else []:
        path = Path(root) / "package_data" / "plotly.min.js"
        if path.is_file():
            return path
    raise NotFound("plotly's offline bundle is not installed (pip install plotly)")


@pages.get("/")
async def dashboard() -> HTMLResponse:
    return HTMLResponse((STATIC / "dashboard.html").read_text())


@pages.get("/view/{job_id}")
async def viewer_shell(job_id: str) -> HTMLResponse:
    return HTMLResponse((STATIC / "viewer.html").read_text())


@data.get("/v1/jobs/{job_id}/view", include_in_schema=False)
async def viewer(job_id: str, queue: QueueDep, settings: SettingsDep, caller: CallerDep) -> HTMLResponse:
    if settings.auth_enabled:
        await queue.get(job_id, with_result=False, owner=caller.scope)  # 404: unknown, or another tenant's
    return HTMLResponse((STATIC / "viewer.html").read_text())


@pages.get("/static/plotly.min.js")
async def plotly_js() -> FileResponse:
    return FileResponse(plotly_bundle(), media_type="text/javascript", headers={"Cache-Control": "max-age=86400"})


@pages.get("/docs")
async def docs() -> HTMLResponse:
    return get_swagger_ui_html(
        openapi_url="/openapi.json",
        title="ManiFoundation Service — API",
        swagger_js_url="/static/swagger/swagger-ui-bundle.js",
        swagger_css_url="/static/swagger/swagger-ui.css",
        swagger_favicon_url="/static/swagger/favicon-32x32.png",
    )


@pages.get("/static/swagger/{name}")
async def swagger_static(name: str) -> FileResponse:
    from swagger_ui_bundle import swagger_ui_path

    path = Path(swagger_ui_path) / name
    if name not in SWAGGER_FILES or not path.is_file():
        raise NotFound(f"no static file {name!r}")
    kinds = {".js": "text/javascript", ".css": "text/css", ".png": "image/png"}
    return FileResponse(path, media_type=kinds[path.suffix], headers={"Cache-Control": "max-age=86400"})


@pages.get("/static/{name}")
async def static(name: str) -> Response:
    path = STATIC / name
    if name.startswith(".") or "/" in name or not path.is_file():
        raise NotFound(f"no static file {name!r}")
    kinds = {".js": "text/javascript", ".css": "text/css", ".html": "text/html"}
    return FileResponse(path, media_type=kinds.get(path.suffix, "application/octet-stream"))


@data.get(
    "/dashboard/data", summary="What the dashboard draws", responses={200: {"model": DashboardPublic}, **READ_ERRORS}
)
async def dashboard_data(request: Request, history: HistoryDep, caller: CallerDep) -> Response:
    """Everything for an admin key (or without keys); a tenant's key sees only its own jobs (see `History`)."""
    return respond(request, await history.snapshot(owner=caller.scope))


@data.get(
    "/v1/jobs/{job_id}/scene",
    summary="A job with its object, for the viewer",
    responses={200: {"model": ScenePublic}, **READ_ERRORS},
)
async def scene(request: Request, job_id: str, queue: QueueDep, caller: CallerDep) -> Response:
    job = await queue.get(job_id, owner=caller.scope)
    return respond(request, services_of(request).scenes.view(job))
