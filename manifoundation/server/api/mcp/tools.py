"""The MCP tools for LLM agents: coarse calls over the service (official ``mcp`` SDK, `MCPServer`).

``upload_object`` (a primitive, points, or a file for ``mani mcp``) → an object id; ``synthesize`` contacts for an
object id; ``plan_manipulation`` (waypoints → trajectory with a grasp per step); ``submit_batch`` and
``get_batch``; ``list_hands``; ``get_job``. Every request is built as the contract's model from the tool's
arguments and handed to the `Backend` — the service's own submission path, or the SDK — so it is validated by
the code that validates HTTP requests, and a bad field comes back as the HTTP API's error body
(``{error, type, detail}``) in the tool's error result. Objects live in an `ObjectStore` per tenant.

Why one module: one tool server; each tool is a short adapter from its arguments to the contract and back, and
they share the argument conventions (object ids, poses as [x, y, z] or [x, y, z, qw, qx, qy, qz], wait_s).
"""

from __future__ import annotations

import json
from collections.abc import Awaitable, Callable
from dataclasses import dataclass
from typing import Annotated, Any, Literal

from mcp.server.mcpserver import Context, MCPServer
from mcp.server.mcpserver.exceptions import ToolError
from pydantic import Field

from manifoundation.contract import MAX_PROPOSALS, ErrorBody, ErrorType, ObjectIn, PlanRequest, SynthesisRequest
from manifoundation.contract.validation import summary
from manifoundation.server.api.errors import InvalidInput
from manifoundation.server.api.mcp.backend import Backend, error_body
from manifoundation.server.api.mcp.objects import ObjectStore
from manifoundation.server.api.mcp.shapes import primitive
from manifoundation.server.api.mcp.summaries import batch_summary, error_summary, hand_summary, job_summary
from manifoundation.server.api.mcp.uploads import Staged, object_from_arrays

MAX_WAIT_S = 60.0
INSTRUCTIONS = """Contact synthesis and manipulation planning for robot hands (ManiFoundation).
Upload an object once (upload_object: a box/sphere/cylinder by size, or points) and use its object_id.
Poses are [x, y, z] (metres) or [x, y, z, qw, qx, qy, qz]. Long work is a job: follow it with get_job."""


@dataclass
class Session:
    """Who a tool call is for: the backend (for this caller), the object namespace, whether files may be read."""

    backend: Backend
    tenant: str
    files: bool = False
    staged: Staged | None = None
    """This call's ``upload_object`` arrays, decoded by the ``/mcp`` endpoint in a body process (large calls)."""


SessionFn = Callable[[Context], Awaitable[Session]]

Pose = Annotated[list[float], Field(description="[x, y, z] m, or [x, y, z, qw, qx, qy, qz]", min_length=3,
                                    max_length=7)]  # fmt: skip
Wait = Annotated[float, Field(ge=0, le=MAX_WAIT_S, description="Seconds to wait for the job to end (0: answer now).")]


def _fail(error: ErrorBody) -> ToolError:
    return ToolError(json.dumps(error_summary(error)))


def _pose(value: list[float]) -> dict[str, Any]:
    """A tool's pose list as the contract's ``{position, quaternion}``."""
    return {"position": value[:3]} if len(value) == 3 else {"position": value[:3], "quaternion": value[3:]}


async def _guarded(call: Awaitable[dict[str, Any]]) -> dict[str, Any]:
    """Run a tool's body; any error becomes the tool's error result carrying the contract's error body."""
    try:
        return await call
    except ToolError:
        raise
    except Exception as exc:
        raise _fail(error_body(exc)) from exc


def build_server(objects: ObjectStore, session_of: SessionFn, *, name: str = "manifoundation") -> MCPServer:
    """The tool server; ``session_of(ctx)`` resolves each call's caller.

    See `manifoundation.server.api.mcp.http` and `.cli`.
    """
    server: MCPServer = MCPServer(name, instructions=INSTRUCTIONS)

    async def _object(session: Session, object_id: str) -> dict[str, Any]:
        return objects.fields(session.tenant, object_id)

    @server.tool(description="The robot hands you can use (built-in and registered by your key).")
    async def list_hands(ctx: Context) -> dict[str, Any]:
        async def body() -> dict[str, Any]:
            session = await session_of(ctx)
            return {"hands": [hand_summary(r) for r in await session.backend.robots()]}

        return await _guarded(body())

    @server.tool(description="Store an object once and get its object_id: a primitive (shape + size, m), or "
                             "points (N×3, 64..200000, optional normals and mesh), or a file path (mani mcp only).")
    async def upload_object(
        ctx: Context,
        shape: Literal["box", "sphere", "cylinder"] | None = None,
        size: Annotated[list[float] | None, Field(description="box [x, y, z]; sphere [r]; cylinder [r, h]")] = None,
        points: list[list[float]] | None = None,
        normals: list[list[float]] | None = None,
        mesh_vertices: list[list[float]] | None = None,
        mesh_faces: list[list[int]] | None = None,
        path: Annotated[str | None, Field(description=".npz .ply .obj .stl on this machine")] = None,
        friction: Annotated[float | None, Field(gt=0, le=5)] = None,
        num_points: Annotated[int, Field(ge=64, le=200_000)] = 1024,
    ) -> dict[str, Any]:
        async def body() -> dict[str, Any]:
            session = await session_of(ctx)
            given = [name for name, v in (("shape", shape), ("points", points), ("path", path)) if v is not None]
            if len(given) != 1:
                raise _fail(ErrorBody.of(ErrorType.VALIDATION_ERROR, "object: give exactly one of shape, points, "
                                         f"path (got {', '.join(given) or 'none'})"))  # fmt: skip
            obj = _uploaded(session, shape, size, points, normals, mesh_vertices, mesh_faces, path, friction,
                            num_points)  # fmt: skip
            stored = objects.put(session.tenant, obj)
            return {"object_id": stored.id, "num_points": obj.num_points, "has_mesh": obj.mesh is not None,
                    "bytes": stored.bytes, "expires_in_s": objects.ttl_s}  # fmt: skip

        return await _guarded(body())

    @server.tool(description="Contacts, forces and a hand pose for an object and a task; waits up to wait_s. "
                             "task: {kind: delta_pose, translation: [x,y,z], rotation: [w,x,y,z]} | "
                             "{kind: force_closure} | {kind: wrench, wrench: [6]}. Each proposal is tested in MuJoCo "
                             "(six pushes, or the executed motion for delta_pose) and success means it held; "
                             "simulate: true searches up to 16 candidates until one holds (a median 0.3-4 s "
                             "more), false skips the test.")
    async def synthesize(
        ctx: Context,
        object_id: str,
        hand: str = "allegro",
        task: dict[str, Any] | None = None,
        method: Literal["auto", "network", "random_contacts", "direct_grasp"] = "auto",
        num_proposals: Annotated[int, Field(ge=1, le=MAX_PROPOSALS)] = 4,
        seed: int = 0,
        simulate: bool | None = None,
        wait_s: Wait = 30.0,
    ) -> dict[str, Any]:
        async def body() -> dict[str, Any]:
            session = await session_of(ctx)
            options = {"method": method, "num_proposals": num_proposals, "seed": seed, "simulate": simulate}
            request = SynthesisRequest.model_validate({
                "object": await _object(session, object_id), "task": task or {"kind": "force_closure"},
                "robot": {"name": hand}, "options": options,
            })  # fmt: skip
            job_id = await session.backend.submit(request)
            return job_summary(await session.backend.job(job_id, wait_s), session.backend.view_url(job_id))

        return await _guarded(body())

    @server.tool(description="Plan a manipulation: the object (object_id) from start through waypoints, around "
                             "obstacles ({kind: box, size, pose: {position, quaternion}, name}), optionally on a "
                             "table (support_plane: its z). Answers a job: a collision-free trajectory, repaired "
                             "waypoints, a verified grasp per step. options: time_limit, translation_step, "
                             "rotation_step, seed, repair (nearest|report), method, num_proposals, contacts.")
    async def plan_manipulation(
        ctx: Context,
        object_id: str,
        start: Pose,
        waypoints: Annotated[list[Pose], Field(min_length=1, max_length=64)],
        hand: str = "allegro",
        obstacles: list[dict[str, Any]] | None = None,
        support_plane: float | None = None,
        options: dict[str, Any] | None = None,
        wait_s: Wait = 0.0,
    ) -> dict[str, Any]:
        async def body() -> dict[str, Any]:
            session = await session_of(ctx)
            scene: dict[str, Any] = {"obstacles": obstacles or []}
            if support_plane is not None:
                scene["support_plane"] = {"height": support_plane}
            request = PlanRequest.model_validate({
                "object": await _object(session, object_id), "start": _pose(start),
                "waypoints": [_pose(w) for w in waypoints], "scene": scene, "robot": {"name": hand},
                "options": {"method": "random_contacts", **(options or {})},
            })  # fmt: skip
            job_id = await session.backend.submit_plan(request)
            return job_summary(await session.backend.job(job_id, wait_s), session.backend.view_url(job_id))

        return await _guarded(body())

    @server.tool(description="Queue many syntheses at once: items [{object_id, task, hand, method, seed}, ...]; "
                             "follow with get_batch.")
    async def submit_batch(ctx: Context, items: Annotated[list[dict[str, Any]], Field(min_length=1)]) -> dict[str, Any]:
        async def body() -> dict[str, Any]:
            session = await session_of(ctx)
            requests = []
            for i, item in enumerate(items):
                unknown = set(item) - {"object_id", "task", "hand", "method", "num_proposals", "seed"}
                if unknown or "object_id" not in item:
                    problem = f"unknown field(s) {sorted(unknown)}" if unknown else "object_id is required"
                    raise _fail(ErrorBody.of(ErrorType.VALIDATION_ERROR, f"items.{i}: {problem}"))
                options = {k: item[k] for k in ("method", "num_proposals", "seed") if k in item}
                requests.append({"object": await _object(session, str(item["object_id"])),
                                 "task": item.get("task") or {"kind": "force_closure"},
                                 "robot": {"name": item.get("hand", "allegro")}, "options": options})  # fmt: skip
            batch = [SynthesisRequest.model_validate(r) for r in requests]
            batch_id = await session.backend.submit_batch(batch)
            return {"batch_id": batch_id, "total": len(batch), "hint": "follow it with get_batch"}

        return await _guarded(body())

    @server.tool(description="A batch's counts by state and one page of its items (each finished one's verdict).")
    async def get_batch(
        ctx: Context, batch_id: str, offset: Annotated[int, Field(ge=0)] = 0,
        limit: Annotated[int, Field(ge=1, le=100)] = 20,
    ) -> dict[str, Any]:  # fmt: skip
        async def body() -> dict[str, Any]:
            session = await session_of(ctx)
            return batch_summary(await session.backend.batch(batch_id, offset, limit))

        return await _guarded(body())

    @server.tool(description="A job's state and progress; once ended its result, plan or error (waits up to "
                             "wait_s for the end).")
    async def get_job(ctx: Context, job_id: str, wait_s: Wait = 0.0) -> dict[str, Any]:
        async def body() -> dict[str, Any]:
            session = await session_of(ctx)
            return job_summary(await session.backend.job(job_id, wait_s), session.backend.view_url(job_id))

        return await _guarded(body())

    return server


def _uploaded(
    session: Session, shape: Literal["box", "sphere", "cylinder"] | None, size: list[float] | None,
    points: list[list[float]] | None, normals: list[list[float]] | None, vertices: list[list[float]] | None,
    faces: list[list[int]] | None, path: str | None, friction: float | None, num_points: int,
) -> ObjectIn:  # fmt: skip
    """The object an upload describes, validated by the contract (a file only where the session allows)."""
    staged = session.staged
    if staged is not None and staged.errors is not None:
        raise InvalidInput(summary(staged.errors), detail=staged.errors)
    if staged is not None and staged.object is not None:
        return staged.object
    properties = {} if friction is None else {"friction": friction}
    if shape is not None:
        try:
            return primitive(shape, size or [], num_points, friction)
        except ValueError as exc:
            raise _fail(ErrorBody.of(ErrorType.VALIDATION_ERROR, str(exc))) from exc
    if path is not None:
        if not session.files:
            raise _fail(ErrorBody.of(ErrorType.VALIDATION_ERROR, "path: this server reads no files (send points "
                                     "or a shape; files only with the local `mani mcp`)"))  # fmt: skip
        from manifoundation.sdk import object_from_file

        try:
            return object_from_file(path, properties=properties)
        except OSError as exc:
            raise _fail(ErrorBody.of(ErrorType.VALIDATION_ERROR, f"path: cannot read {path!r} ({exc})")) from exc
    return object_from_arrays(points, normals, vertices, faces, friction)
