"""`/v1/robots`: the hands workers can use; register a URDF (validated by a worker, stored in the queue)."""

from __future__ import annotations

import re

from fastapi import APIRouter, Request
from starlette.responses import Response

from clients.schemas import ErrorBody, RobotPublic, RobotRegister, WireModel
from service.deps import Authorized, CallerDep, QueueDep, RobotsDep, SettingsDep
from service.errors import Conflict
from service.negotiation import body_openapi, read_model, respond
from service.responses import ERRORS, READ_ERRORS

MESH_FILE = re.compile(r"<mesh\b[^>]*\bfilename\s*=\s*[\"']([^\"']{1,300})[\"']")
router = APIRouter(prefix="/v1/robots", tags=["robots"], dependencies=[Authorized])


class RobotList(WireModel):
    """Answer of ``GET /v1/robots`` (service-local wrapper)."""

    robots: list[RobotPublic]


@router.get("", summary="Built-in and registered hands", responses={200: {"model": RobotList}, **READ_ERRORS})
async def list_robots(request: Request, robots: RobotsDep, caller: CallerDep) -> Response:
    return respond(request, RobotList(robots=await robots.all(caller.tenant, fresh=True)))


@router.get(
    "/{name}",
    summary="One hand: DoF, joints, limits, fingertips",
    responses={200: {"model": RobotPublic}, **READ_ERRORS},
)
async def get_robot(request: Request, name: str, robots: RobotsDep, caller: CallerDep) -> Response:
    return respond(request, await robots.get(name, caller.tenant))


@router.post(
    "",
    status_code=201,
    summary="Register a URDF hand (validated with the hardened loader by a worker)",
    openapi_extra=body_openapi("RobotRegister"),
    responses={201: {"model": RobotPublic}, 409: {"model": ErrorBody, "description": "A built-in name"}, **ERRORS},
)
async def register_robot(
    request: Request, queue: QueueDep, robots: RobotsDep, settings: SettingsDep, caller: CallerDep
) -> Response:
    """Registered in the caller's namespace: another key's hand of the same name is another hand."""
    body = await read_model(request, RobotRegister, settings.max_robot_bytes)
    existing = await robots.find(body.name, caller.tenant)
    if existing is not None and existing.builtin:
        raise Conflict(f"name: {body.name!r} is a built-in hand; choose another name")
    if existing is None:
        mine = [r for r in await robots.all(caller.tenant, fresh=True) if not r.builtin]
        if len(mine) >= settings.max_robots:
            raise Conflict(
                f"{len(mine)} hands registered, at most {settings.max_robots} per key (MANI_MAX_ROBOTS); "
                "DELETE /v1/robots/{name} one first"
            )
    robot = await queue.register_robot(body, timeout=settings.robot_register_timeout, owner=caller.tenant)
    robots.forget(caller.tenant)
    meshes = sorted(set(MESH_FILE.findall(body.urdf)))
    if meshes:  # the hardened loader never opens files: say so rather than drop them silently
        shown = ", ".join(meshes[:5]) + (f" and {len(meshes) - 5} more" if len(meshes) > 5 else "")
        note = f"urdf: {len(meshes)} mesh file(s) not loaded ({shown}): the hardened loader reads no files"
        robot = robot.model_copy(update={"warnings": [*robot.warnings, note]})
    url = str(request.url_for("get_robot", name=robot.name))
    return respond(request, robot, status=201, headers={"Location": url})


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
