"""Issue 62 on the real front ends and backends: the per-key robot limits (``MANI_MAX_ROBOTS``,
``MANI_MAX_ROBOT_STORE_BYTES``) hold under concurrency and over gRPC: one atomic reservation in the store."""

from __future__ import annotations

import time
from collections.abc import Iterator
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import grpc
import httpx
import pytest

from manifoundation.contract.protos.v1 import manifoundation_pb2 as pb
from manifoundation.contract.protos.v1 import manifoundation_pb2_grpc as pb_grpc
from manifoundation.server.api.app import create_app
from manifoundation.server.api.settings import Settings

from .server import free_port, serving
from .workers import start_queue_and_workers

KEYS = ["quota-race-key", "quota-bytes-key", "quota-bytes-race-key"]
MAX_ROBOTS, STORE_BYTES = 20, 300_000
URDF = '<robot name="r"><link name="a"/><link name="b"/><joint name="j" type="revolute"><parent link="a"/>' \
       '<child link="b"/><limit lower="0" upper="1"/></joint></robot>'  # fmt: skip
BIG = URDF + " " * 200_000  # 200 kB stored: one fits the 300 kB quota, two do not


@dataclass
class Front:
    http: httpx.Client
    grpc: pb_grpc.ManiFoundationStub


@pytest.fixture(scope="module", params=["embedded", "redis"])
def front(request: pytest.FixtureRequest) -> Iterator[Front]:
    with start_queue_and_workers(request, stage_seconds=0.0) as queue:
        port = free_port()
        settings = Settings(
            api_keys=KEYS, rate_limit_per_s=0, max_robots=MAX_ROBOTS, max_robot_store_bytes=STORE_BYTES,
            max_robot_bytes=400_000, robots_cache_s=0, grpc_port=port,
        )  # fmt: skip
        with (
            serving(create_app(settings, queue=queue, grpc=True)) as base,
            httpx.Client(base_url=base, timeout=60) as client,
            grpc.insecure_channel(f"127.0.0.1:{port}") as channel,
        ):
            deadline = time.monotonic() + 120
            while client.get("/readyz").status_code != 200:
                assert time.monotonic() < deadline
                time.sleep(0.1)
            yield Front(client, pb_grpc.ManiFoundationStub(channel))


def auth(key: str) -> dict[str, str]:
    return {"Authorization": f"Bearer {key}"}


def register(front: Front, key: str, name: str, urdf: str = URDF) -> httpx.Response:
    return front.http.post("/v1/robots", json={"name": name, "urdf": urdf, "fingertips": ["b"]}, headers=auth(key))


def test_the_robot_count_holds_under_60_concurrent_registrations(front: Front) -> None:
    with ThreadPoolExecutor(12) as pool:
        codes = list(pool.map(lambda i: register(front, KEYS[0], f"race{i}").status_code, range(60)))
    assert sorted(codes) == [201] * MAX_ROBOTS + [409] * (60 - MAX_ROBOTS)
    mine = [r for r in front.http.get("/v1/robots", headers=auth(KEYS[0])).json()["robots"] if not r["builtin"]]
    assert len(mine) == MAX_ROBOTS
    assert register(front, KEYS[0], "race0").status_code == 201  # replacing one of its own still fits


def test_grpc_register_robot_counts_the_stored_bytes_as_http_does(front: Front) -> None:
    key = KEYS[1]
    assert register(front, key, "big1", BIG).status_code == 201
    over = register(front, key, "big2", BIG)
    assert over.status_code == 409 and "MANI_MAX_ROBOT_STORE_BYTES" in over.json()["error"]
    message = pb.RobotRegister(name="big2", urdf=BIG, fingertips=["b"])
    with pytest.raises(grpc.RpcError) as caught:
        front.grpc.RegisterRobot(message, metadata=(("authorization", f"Bearer {key}"),), timeout=60)
    assert caught.value.code() is grpc.StatusCode.FAILED_PRECONDITION
    assert caught.value.details() == over.json()["error"]  # one rule, one message
    mine = [r["name"] for r in front.http.get("/v1/robots", headers=auth(key)).json()["robots"] if not r["builtin"]]
    assert mine == ["big1"]


def test_the_stored_bytes_hold_under_concurrent_registrations_over_both_front_ends(front: Front) -> None:
    key, metadata = KEYS[2], (("authorization", f"Bearer {KEYS[2]}"),)

    def over_grpc(i: int) -> str:
        try:
            front.grpc.RegisterRobot(pb.RobotRegister(name=f"g{i}", urdf=BIG, fingertips=["b"]), metadata=metadata)
        except grpc.RpcError as e:
            return "409" if e.code() is grpc.StatusCode.FAILED_PRECONDITION else str(e.code())
        return "201"

    with ThreadPoolExecutor(8) as pool:
        calls = [pool.submit(lambda i=i: str(register(front, key, f"h{i}", BIG).status_code)) for i in range(4)]
        calls += [pool.submit(over_grpc, i) for i in range(4)]
        codes = sorted(c.result() for c in calls)
    assert codes == ["201"] + ["409"] * 7
