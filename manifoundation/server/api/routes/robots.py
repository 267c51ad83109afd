"""`/v1/robots`: the hands workers can use; register a URDF or MJCF, alone or in an archive with its meshes
(validated and built by a worker, stored in the queue), look at one at rest, remove one.

Registered hands belong to the key that registered them: at most ``max_robots`` of them and
``max_robot_store_bytes`` of descriptions and archives per key (409 beyond: DELETE one first).
"""

from __future__ import annotations

import re

from fastapi import APIRouter, Request
from starlette.responses import HTMLResponse, Response

from manifoundation.contract import ErrorBody, RobotList, RobotPreview, RobotPublic, RobotRegister
from manifoundation.server.api.deps import Authorized, CallerDep, QueueDep, RobotsDep, SettingsDep
from manifoundation.server.api.errors import Conflict, NotFound
from manifoundation.server.api.negotiation import body_openapi, read_model, respond
from manifoundation.server.api.responses import ERRORS, READ_ERRORS
from manifoundation.server.api.robot_page import robot_page

MESH_FILE = re.compile(r"<mesh\b[^>]*\bfilename\s*=\s*[\"']([^\"']{1,300})[\"']")
router = APIRouter(prefix="/v1/robots", tags=["robots"], dependencies=[Authorized])


def _brief(robot: RobotPublic, request: Request) -> RobotPublic:
    """A hand without its preview data, with its view page's URL when it has one."""
    if robot.builtin or (robot.preview is None and robot.view_url is None):
        return robot.model_copy(update={"preview": None})
    return robot.model_copy(update={"preview": None, "view_url": str(request.url_for("view_robot", name=robot.name))})


@router.get("", summary="Built-in and registered hands", responses={200: {"model": RobotList}, **READ_ERRORS})
async def list_robots(request: Request, robots: RobotsDep, caller: CallerDep) -> Response:
    return respond(request, RobotList(robots=[_brief(r, request) for r in await robots.all(caller.tenant, fresh=True)]))


@router.get(
    "/{name}",
    summary="One hand: DoF, joints, limits, fingertips",
    responses={200: {"model": RobotPublic}, **READ_ERRORS},
)
async def get_robot(request: Request, name: str, robots: RobotsDep, caller: CallerDep) -> Response:
    return respond(request, _brief(await robots.get(name, caller.tenant), request))


@router.get(
    "/{name}/preview",
    summary="A registered hand at rest: coarse meshes, collision spheres, pad samples, fingertips (palm frame)",
    responses={200: {"model": RobotPreview}, **READ_ERRORS},
)
async def robot_preview(request: Request, name: str, robots: RobotsDep, caller: CallerDep) -> Response:
    robot = await robots.get(name, caller.tenant)
    if robot.preview is None:
        raise NotFound(f"{name!r} has no preview (built-in hands: see `mani hands`)")
    return respond(request, robot.preview)


@router.get(
    "/{name}/view", summary="A page drawing the hand at rest with its spheres and pads", include_in_schema=False
)
async def view_robot(name: str, robots: RobotsDep, caller: CallerDep) -> HTMLResponse:
    robot = await robots.get(name, caller.tenant)
    if robot.preview is None:
        raise NotFound(f"{name!r} has no preview (built-in hands: see `mani hands`)")
    return HTMLResponse(robot_page(robot.name, robot.preview.model_dump(mode="json"), _summary(robot)))


def _summary(robot: RobotPublic) -> str:
    pads = ", ".join(f"{a:.1f}" for a in robot.pad_area_cm2 or [])
    return (
        f"{robot.name}: {robot.dof} DoF, palm {robot.palm}, fingertips {', '.join(robot.fingertips)}, "
        f"{robot.num_spheres} spheres, pads {pads} cm²"
    )


@router.post(
    "",
    status_code=201,
    summary="Register a hand: a URDF or MJCF, alone or in a zip/tar with its meshes; `palm` cuts it from a robot",
    openapi_extra=body_openapi("RobotRegister"),
    responses={
        201: {"model": RobotPublic},
        409: {"model": ErrorBody, "description": "A built-in name, or the key's robot count or bytes reached"},
        504: {
            "model": ErrorBody,
            "description": "Still loading at MANI_ROBOT_REGISTER_TIMEOUT: its worker was stopped and replaced",
        },
        **ERRORS,
    },
)
async def register_robot(request: Request, robots: RobotsDep, settings: SettingsDep, caller: CallerDep) -> Response:
    """Registered in the caller's namespace: another key's hand of the same name is another hand."""
    body = await read_model(request, RobotRegister, settings.max_robot_bytes)
    robot = await robots.register(
        body, caller.tenant, limits=settings.robot_limits(), timeout=settings.robot_register_timeout
    )
    meshes = sorted(set(MESH_FILE.findall(body.urdf))) if body.urdf is not None else []
    if meshes:  # the hardened loader never opens files: say so rather than drop them silently
        shown = ", ".join(meshes[:5]) + (f" and {len(meshes) - 5} more" if len(meshes) > 5 else "")
        note = f"urdf: {len(meshes)} mesh file(s) not loaded ({shown}): the hardened loader reads no files"
        robot = robot.model_copy(update={"warnings": [*robot.warnings, note]})
    url = str(request.url_for("get_robot", name=robot.name))
    return respond(request, _brief(robot, request), status=201, headers={"Location": url})


@router.delete(
    "/{name}",
    status_code=204,
    summary="Remove a hand this key registered (jobs naming it afterwards: 404)",
    responses={
        204: {"description": "Removed"},
        409: {"model": ErrorBody, "description": "A built-in hand"},
        **READ_ERRORS,
    },
)
async def delete_robot(name: str, queue: QueueDep, robots: RobotsDep, caller: CallerDep) -> Response:
    existing = await robots.find(name, caller.tenant)
    if existing is not None and existing.builtin:
        raise Conflict(f"name: {name!r} is a built-in hand; it cannot be removed")
    await queue.delete_robot(name, owner=caller.tenant)
    robots.forget(caller.tenant)
    return Response(status_code=204)
