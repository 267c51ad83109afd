"""`mani mcp` over stdio, launched as a subprocess by the mcp SDK's own client, in front of a real service: the
same tools, calling the service with the SDK and the key it was given; files on this machine may be uploaded."""

from __future__ import annotations

import asyncio
import json
import os
import sys
from pathlib import Path
from typing import Any

import pytest
from mcp import Client, StdioServerParameters

from ..science import HAND, KEY, Science

BOX = Path(__file__).resolve().parents[3] / "examples" / "data" / "box.npz"


async def _session(science: Science) -> dict[str, Any]:
    command = StdioServerParameters(
        command=sys.executable, args=["-m", "manifoundation.cli.main", "mcp", "--url", science.base],
        env={**os.environ, "MANI_API_KEY": KEY},
    )  # fmt: skip
    seen: dict[str, Any] = {}
    async with Client(command) as client:
        seen["hands"] = (await client.call_tool("list_hands", {})).structured_content
        upload = (await client.call_tool("upload_object", {"path": str(BOX)})).structured_content
        seen["upload"] = upload
        seen["plan"] = (await client.call_tool("plan_manipulation", {
            "object_id": upload["object_id"], "hand": HAND, "start": [0, 0, 0.1], "waypoints": [[0, 0.1, 0.15]],
            "options": {"contacts": False, "translation_step": 0.05}, "wait_s": 30,
        })).structured_content  # fmt: skip
        missing = await client.call_tool("get_job", {"job_id": "no-such-job"})
        text = missing.content[0].text
        seen["missing"] = (missing.is_error, json.loads(text[text.index("{") :]))
    return seen


@pytest.mark.slow  # ≈ 4 s: a subprocess importing the SDK and the mcp package; the HTTP twin runs by default
def test_stdio_tools_go_through_the_service(science: Science) -> None:
    seen = asyncio.run(_session(science))
    assert [h["name"] for h in seen["hands"]["hands"]] == [HAND]
    assert seen["upload"]["num_points"] > 64 and seen["upload"]["object_id"].startswith("obj_")
    plan = seen["plan"]
    assert plan["state"] == "succeeded" and plan["plan"]["success"], plan
    # 11.2 cm in steps of at most 5 cm: 3 steps, 4 poses
    assert plan["plan"]["poses"] == 4 and plan["plan"]["waypoints"][-1]["position"] == [0.0, 0.1, 0.15]
    assert seen["missing"][0] and seen["missing"][1]["type"] == "NotFound"
