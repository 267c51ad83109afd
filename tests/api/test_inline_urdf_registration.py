"""A URDF registered alone without `fingertips` gets the leaf links, as an archive does and as `mani robots add
--help` says (the contract used to refuse it, so the CLI's own default could never be used)."""

from __future__ import annotations

import time
from collections.abc import Iterator

import httpx
import pytest

from manifoundation.contract import RobotRegister
from manifoundation.server.api.app import create_app
from manifoundation.server.api.settings import Settings

from .server import serving
from .workers import start_queue_and_workers

PIPELINE = "manifoundation.server.worker.models_pipeline:ModelsPipeline"
TWO_FINGERS = """<?xml version="1.0"?>
<robot name="two">
  <link name="palm"><collision><geometry><box size="0.04 0.04 0.02"/></geometry></collision></link>
  <link name="left"><collision><origin xyz="0 0 0.03"/><geometry><box size="0.01 0.01 0.06"/></geometry>
    </collision></link>
  <link name="right"><collision><origin xyz="0 0 0.03"/><geometry><box size="0.01 0.01 0.06"/></geometry>
    </collision></link>
  <joint name="j_left" type="revolute"><parent link="palm"/><child link="left"/><origin xyz="0.02 0 0.01"/>
    <axis xyz="0 1 0"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
  <joint name="j_right" type="revolute"><parent link="palm"/><child link="right"/><origin xyz="-0.02 0 0.01"/>
    <axis xyz="0 1 0"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
</robot>"""


def test_the_contract_accepts_an_inline_urdf_without_fingertips() -> None:
    assert RobotRegister(name="two", urdf=TWO_FINGERS).fingertips is None


@pytest.fixture(scope="module")
def base(request: pytest.FixtureRequest) -> Iterator[str]:
    settings = Settings(robot_register_timeout=120, rate_limit_per_s=0, robots_cache_s=0)
    with (
        start_queue_and_workers(request, pipeline=PIPELINE, hands=["panda_gripper"]) as queue,
        serving(create_app(settings, queue=queue)) as url,
    ):
        deadline = time.monotonic() + 240
        while not httpx.get(f"{url}/v1/robots", timeout=10).json()["robots"]:
            assert time.monotonic() < deadline, "no worker published its hands"
            time.sleep(0.5)
        yield url


def test_an_inline_urdf_without_fingertips_registers_with_its_leaf_links(base: str) -> None:
    answer = httpx.post(f"{base}/v1/robots", json={"name": "two-fingers", "urdf": TWO_FINGERS}, timeout=120)
    assert answer.status_code == 201, answer.text
    robot = answer.json()
    assert sorted(robot["fingertips"]) == ["left", "right"] and robot["dof"] == 2
