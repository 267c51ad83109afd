"""The MCP tools at ``/mcp`` on a real service (science in the worker), called with the mcp SDK's own client over
streamable HTTP: the same keys as ``/v1``, objects and jobs per key, errors as the HTTP API's bodies."""

from __future__ import annotations

import asyncio
import json
from typing import Any

import httpx
import pytest
from mcp import Client
from mcp.client.streamable_http import streamable_http_client
from mcp.shared._httpx_utils import create_mcp_http_client

from ..science import HAND, KEY, OTHER, Science


def _client(science: Science, key: str) -> Client:
    http = create_mcp_http_client(headers={"Authorization": f"Bearer {key}"})
    return Client(streamable_http_client(f"{science.base}/mcp", http_client=http))


def _error(result: Any) -> dict[str, Any]:
    """The contract's error body a failed tool call carries (after the SDK's "Error executing tool ..." prefix)."""
    assert result.is_error, result
    text = result.content[0].text
    return dict(json.loads(text[text.index("{") :]))


async def _session(science: Science) -> dict[str, Any]:
    seen: dict[str, Any] = {}
    async with _client(science, KEY) as mine, _client(science, OTHER) as theirs:
        seen["tools"] = {t.name for t in (await mine.list_tools()).tools}
        seen["hands"] = (await mine.call_tool("list_hands", {})).structured_content
        upload = await mine.call_tool("upload_object", {"shape": "box", "size": [0.04, 0.06, 0.06], "friction": 0.8,
                                                        "num_points": 512})  # fmt: skip
        object_id = upload.structured_content["object_id"]
        seen["upload"] = upload.structured_content
        seen["synth"] = (await mine.call_tool("synthesize", {
            "object_id": object_id, "hand": HAND, "method": "direct_grasp", "num_proposals": 1, "wait_s": 60,
        })).structured_content  # fmt: skip
        seen["simulated"] = (await mine.call_tool("synthesize", {
            "object_id": object_id, "hand": HAND, "method": "direct_grasp", "num_proposals": 1, "simulate": True,
            "wait_s": 60,
        })).structured_content  # fmt: skip
        seen["plan"] = (await mine.call_tool("plan_manipulation", {
            "object_id": object_id, "hand": HAND, "start": [0, 0, 0.1], "waypoints": [[0.1, 0, 0.1]],
            "support_plane": 0.0, "options": {"contacts": False}, "wait_s": 30,
        })).structured_content  # fmt: skip
        seen["bad_pose"] = _error(await mine.call_tool("plan_manipulation", {
            "object_id": object_id, "hand": HAND, "start": [0, 0, 0.1], "waypoints": [[0.1, 0, 0.1, 0, 0, 0, 0]],
        }))  # fmt: skip
        seen["bad_hand"] = _error(await mine.call_tool("synthesize", {"object_id": object_id, "hand": "nope"}))
        seen["foreign_object"] = _error(await theirs.call_tool("synthesize", {"object_id": object_id, "hand": HAND}))
        job_id = seen["synth"]["job_id"]
        seen["foreign_job"] = _error(await theirs.call_tool("get_job", {"job_id": job_id}))
        seen["own_job"] = (await mine.call_tool("get_job", {"job_id": job_id})).structured_content
    return seen


def test_tools_act_for_the_key_through_the_service(science: Science) -> None:
    seen = asyncio.run(_session(science))
    assert {"upload_object", "synthesize", "plan_manipulation", "submit_batch", "get_batch", "list_hands",
            "get_job"} <= seen["tools"]  # fmt: skip
    assert [h["name"] for h in seen["hands"]["hands"]] == [HAND]
    assert seen["upload"]["num_points"] == 512 and seen["upload"]["has_mesh"]
    synth = seen["synth"]
    assert synth["state"] == "succeeded" and synth["kind"] == "synthesis", synth
    assert synth["result"]["proposals"] == 1 and synth["view_url"].endswith(f"/view/{synth['job_id']}")
    best = synth["result"]["best"]
    assert len(best["contact_points"]) == len(best["fingertips"]) == 4 and len(best["joint_values"]) == 16
    # tested by default (a check of the answer): success only where the object held
    assert best["physics"]["test"] == "closure" and (not best["success"] or best["physics"]["held"])
    tested = seen["simulated"]["result"]["best"]  # a search asked: the test's verdict, success only if held
    assert tested["physics"]["test"] == "closure" and tested["physics"]["reason"] in ("held", "moved", "penetration")
    assert not tested["success"] or tested["physics"]["held"]
    plan = seen["plan"]
    assert plan["state"] == "succeeded" and plan["plan"]["success"] and plan["plan"]["segments"] == 1, plan
    assert plan["plan"]["waypoints"][-1]["position"] == [0.1, 0.0, 0.1]
    assert seen["bad_pose"]["type"] == "ValidationError"
    assert seen["bad_pose"]["detail"][0]["field"] == "waypoints.0.quaternion"
    assert seen["bad_hand"]["type"] == "UnknownHand" and seen["bad_hand"]["detail"][0]["field"] == "robot.name"
    assert seen["foreign_object"]["type"] == "NotFound" and seen["foreign_object"]["detail"][0]["field"] == "object_id"
    assert seen["foreign_job"]["type"] == "NotFound"  # another key's job does not exist for it
    assert seen["own_job"]["state"] == "succeeded"


def test_the_endpoint_needs_a_key_like_v1(science: Science) -> None:
    body = {"jsonrpc": "2.0", "id": 1, "method": "tools/list"}
    headers = {"Accept": "application/json, text/event-stream"}
    answer = httpx.post(f"{science.base}/mcp", json=body, headers=headers)
    assert answer.status_code == 401 and answer.json()["type"] == "Unauthorized"
    wrong = httpx.post(f"{science.base}/mcp", json=body, headers={**headers, "Authorization": "Bearer not-a-key-1"})
    assert wrong.status_code == 401


@pytest.mark.slow
def test_a_batch_of_uploaded_objects(science: Science) -> None:
    async def run() -> dict[str, Any]:
        async with _client(science, KEY) as mine:
            upload = await mine.call_tool("upload_object", {"shape": "cylinder", "size": [0.03, 0.1]})
            item = {"object_id": upload.structured_content["object_id"], "hand": HAND, "method": "direct_grasp",
                    "num_proposals": 1}  # fmt: skip
            batch = (await mine.call_tool("submit_batch", {"items": [item, {**item, "seed": 1}]})).structured_content
            for _ in range(600):
                page = (await mine.call_tool("get_batch", {"batch_id": batch["batch_id"]})).structured_content
                if page["done"]:
                    return dict(page)
                await asyncio.sleep(0.1)
            raise AssertionError("the batch did not finish")

    page = asyncio.run(run())
    assert page["total"] == 2 and page["counts"] == {"succeeded": 2}
    assert all(item["best"] is not None for item in page["items"])
