"""An agent's MCP session with the service, as an LLM client would drive it (the official mcp SDK's client).

It lists the hands, uploads the cup of `planner_waypoints.py` once (an object id from then on), asks for a grasp
that lifts it, queues a small batch, and plans "put the cup in the box" with the planner's waypoints (one inside
the kettle: repaired), following the plan job with ``get_job`` until it ends.

    .venv/bin/mani serve &                                              # the service, MCP at /mcp
    .venv/bin/python examples/mcp_session.py                            # streamable HTTP to http://127.0.0.1:8000/mcp
    .venv/bin/python examples/mcp_session.py --stdio                    # or: `mani mcp` as a subprocess (stdio)

``--api-key`` (or ``MANI_API_KEY``) when the service has keys.
"""

from __future__ import annotations

import argparse
import asyncio
import json
import os
import sys
import time
from typing import Any


def _show(name: str, result: Any) -> dict[str, Any]:
    """Print a tool's answer (or its error) briefly; the structured answer."""
    if result.is_error:
        print(f"{name}: ERROR {result.content[0].text}")
        return {}
    data = dict(result.structured_content or {})
    text = json.dumps(data)
    print(f"{name}: {text[:300]}{' ...' if len(text) > 300 else ''}")
    return data


async def session(client: Any, hand: str) -> int:
    from planner_waypoints import cup_in_box_request, wire_request

    plan = wire_request(cup_in_box_request(hand, "random_contacts", 0))
    _show("list_hands", await client.call_tool("list_hands", {}))
    cup = plan.object
    upload = _show("upload_object", await client.call_tool("upload_object", {
        "points": cup.points.tolist(), "normals": cup.normals.tolist(), "friction": 0.8,
        "mesh_vertices": cup.mesh.vertices.tolist(), "mesh_faces": cup.mesh.faces.tolist(),
    }))  # fmt: skip
    object_id = upload["object_id"]
    lift = {"kind": "delta_pose", "translation": [0, 0, 0.05], "rotation": [1, 0, 0, 0]}
    _show("synthesize", await client.call_tool("synthesize", {
        "object_id": object_id, "hand": hand, "task": lift, "method": "random_contacts", "wait_s": 60,
    }))  # fmt: skip
    batch = _show("submit_batch", await client.call_tool("submit_batch", {"items": [
        {"object_id": object_id, "hand": hand, "task": lift, "method": "random_contacts", "seed": seed}
        for seed in (1, 2)
    ]}))  # fmt: skip
    pose = [*plan.start.position, *plan.start.quaternion]
    obstacles = [o.model_dump(mode="json", exclude_none=True) for o in plan.scene.obstacles]
    t0 = time.perf_counter()
    job = _show("plan_manipulation", await client.call_tool("plan_manipulation", {
        "object_id": object_id, "hand": hand, "start": pose, "obstacles": obstacles, "support_plane": 0.0,
        "waypoints": [[*w.position, *w.quaternion] for w in plan.waypoints],
        "options": plan.options.model_dump(mode="json", exclude_unset=True),
    }))  # fmt: skip
    while job.get("state") not in ("succeeded", "failed", "cancelled", "expired"):
        job = dict((await client.call_tool("get_job", {"job_id": job["job_id"], "wait_s": 30})).structured_content)
        p = job.get("progress", {})
        print(f"get_job: {job.get('state')} {p.get('stage')} {p.get('completed')}/{p.get('total')}")
    summary = job.get("plan", {})
    print(f"plan: success {summary.get('success')}, {summary.get('poses')} poses, repairs {summary.get('repairs')}, "
          f"grasps {summary.get('grasps')}, re-grasps at {summary.get('regrasps')} "
          f"({time.perf_counter() - t0:.1f} s); view: {job.get('view_url')}")  # fmt: skip
    _show("get_batch", await client.call_tool("get_batch", {"batch_id": batch["batch_id"]}))
    return 0 if summary.get("success") else 1


async def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--url", default=os.environ.get("MANI_URL", "http://127.0.0.1:8000"),
                        help="the service (env MANI_URL; default %(default)s)")  # fmt: skip
    parser.add_argument("--api-key", default=os.environ.get("MANI_API_KEY"))
    parser.add_argument("--stdio", action="store_true", help="run `mani mcp` as a subprocess instead of HTTP")
    parser.add_argument("--hand", default="allegro")
    args = parser.parse_args()

    from mcp import Client, StdioServerParameters
    from mcp.client.streamable_http import streamable_http_client
    from mcp.shared._httpx_utils import create_mcp_http_client

    t0 = time.perf_counter()
    if args.stdio:
        env = {**os.environ, **({"MANI_API_KEY": args.api_key} if args.api_key else {})}
        command = ["-m", "manifoundation.cli.main", "mcp", "--url", args.url]
        server: Any = StdioServerParameters(command=sys.executable, args=command, env=env)
    else:
        headers = {"Authorization": f"Bearer {args.api_key}"} if args.api_key else {}
        server = streamable_http_client(f"{args.url}/mcp", http_client=create_mcp_http_client(headers=headers))
    async with Client(server) as client:
        code = await session(client, args.hand)
    print(f"session: {time.perf_counter() - t0:.1f} s")
    return code


if __name__ == "__main__":
    raise SystemExit(asyncio.run(main()))
