"""Tenant isolation over every route, on the real queue backends (embedded; Redis when reachable).

With ``MANI_API_KEYS=A,B`` each key is a tenant: B gets 404 (the same answer as for an unknown id) for A's jobs,
batches, scenes, event streams, views and registered robots, never sees A's ids in lists or on the dashboard, and
registering a hand of the same name makes B's own hand (A's jobs keep running on A's URDF). An admin key reads
everything.
"""

from __future__ import annotations

import time
from collections.abc import Iterator
from dataclasses import dataclass

import httpx
import pytest

from manifoundation.server.api.app import create_app
from manifoundation.server.api.errors import route_table
from manifoundation.server.api.settings import Settings

from .helpers import request_body
from .server import serving
from .workers import start_queue_and_workers

A, B, ADMIN = "tenant-a-key-1", "tenant-b-key-2", "operator-key-3"
HAND = "test_gripper"


def urdf(joints: int) -> str:
    links = "".join(f'<link name="l{i}"/>' for i in range(joints + 1))
    chain = "".join(
        f'<joint name="j{i}" type="revolute"><parent link="l{i}"/><child link="l{i + 1}"/>'
        '<limit lower="0" upper="1"/></joint>'
        for i in range(joints)
    )
    return f'<robot name="r">{links}{chain}</robot>'


@dataclass
class World:
    base: str
    clients: dict[str, httpx.Client]
    job: str  # A's finished job
    long_job: str  # A's running job
    batch: str  # A's batch

    def as_(self, who: str) -> httpx.Client:
        return self.clients[who]


@pytest.fixture(scope="module", params=["embedded", "redis"])
def world(request: pytest.FixtureRequest) -> Iterator[World]:
    with start_queue_and_workers(request, stage_seconds=0.01, iterations=500) as queue:
        settings = Settings(api_keys=[A, B], admin_keys=[ADMIN], rate_limit_per_s=0, sync_wait_max=20,
                            auth_failures_burst=50)  # one keyless call per route: more than the default 10
        with serving(create_app(settings, queue=queue)) as base:
            clients = {
                k: httpx.Client(base_url=base, headers={"Authorization": f"Bearer {k}"}, timeout=60)
                for k in (A, B, ADMIN)
            }
            clients["none"] = httpx.Client(base_url=base, timeout=60)
            deadline = time.monotonic() + 120
            while clients[A].get("/readyz").status_code != 200:
                assert time.monotonic() < deadline, "no worker became ready"
                time.sleep(0.1)
            a = clients[A]
            for who, joints in ((A, 1), (B, 2)):  # the same name: two hands
                registered = clients[who].post("/v1/robots", json={"name": "shared", "urdf": urdf(joints),
                                                                  "fingertips": [f"l{joints}"]})  # fmt: skip
                assert registered.status_code == 201, registered.text
            only_a = a.post("/v1/robots", json={"name": "only-a", "urdf": urdf(1), "fingertips": ["l1"]})
            assert only_a.status_code == 201, only_a.text
            done = a.post("/v1/synthesize", json=request_body(HAND, max_iterations=1))
            assert done.status_code == 200, done.text
            long_job = a.post("/v1/jobs", json=request_body(HAND, max_iterations=500)).json()["id"]  # ≈ 5 s
            batch = a.post("/v1/batches", json={"requests": [request_body(HAND, max_iterations=1)] * 2})
            assert batch.status_code == 202, batch.text
            yield World(base, clients, done.headers["x-job-id"], long_job, batch.json()["id"])
            a.delete(f"/v1/jobs/{long_job}")
            for client in clients.values():
                client.close()


def routes(world: World) -> list[tuple[str, str]]:
    """Every route that names one of A's resources (method, path)."""
    job, batch = world.job, world.batch
    return [
        ("GET", f"/v1/jobs/{job}"),
        ("GET", f"/v1/jobs/{job}/events"),
        ("GET", f"/v1/jobs/{job}/scene"),
        ("GET", f"/v1/jobs/{job}/view"),
        ("DELETE", f"/v1/jobs/{world.long_job}"),
        ("GET", f"/v1/batches/{batch}"),
        ("GET", "/v1/robots/only-a"),
        ("GET", "/v1/robots/only-a/preview"),
        ("GET", "/v1/robots/only-a/view"),
        ("DELETE", "/v1/robots/only-a"),
    ]


def test_other_tenant_gets_404_like_an_unknown_id(world: World) -> None:
    for method, path in routes(world):
        theirs = world.as_(B).request(method, path)
        assert theirs.status_code == 404, (method, path, theirs.text)
        unknown = world.as_(B).request(method, path.replace(world.job, "0" * 32).replace(world.batch, "0" * 32)
                                       .replace(world.long_job, "0" * 32).replace("only-a", "nobody"))  # fmt: skip
        assert unknown.status_code == 404 and theirs.json()["type"] == unknown.json()["type"]  # nothing to tell apart
        assert theirs.json()["type"] in ("NotFound", "UnknownHand")
        assert world.as_("none").request(method, path).status_code == 401, (method, path)
    assert world.as_(A).get(f"/v1/jobs/{world.long_job}").json()["state"] != "cancelled"  # B's DELETE did nothing


def test_owner_and_admin_read_everything_of_their_own(world: World) -> None:
    for method, path in routes(world):
        if method == "GET":
            for who in (A, ADMIN) if "/robots/" not in path else (A,):
                answer = world.as_(who).get(path)
                assert answer.status_code == 200, (who, path, answer.text)
    assert world.as_(ADMIN).get("/v1/robots/only-a").status_code == 404  # robots: each key its own namespace


def test_lists_and_dashboard_show_only_the_callers_jobs(world: World) -> None:
    b_job = world.as_(B).post("/v1/jobs", json=request_body(HAND, max_iterations=1)).json()["id"]
    mine = {j["id"] for j in world.as_(B).get("/v1/jobs").json()["jobs"]}
    assert b_job in mine and world.job not in mine and world.long_job not in mine
    assert {world.job, b_job} <= {j["id"] for j in world.as_(ADMIN).get("/v1/jobs").json()["jobs"]}
    b_dash = world.as_(B).get("/dashboard/data").text
    assert b_job in b_dash and world.job not in b_dash and world.long_job not in b_dash
    admin_dash = world.as_(ADMIN).get("/dashboard/data").text
    assert world.job in admin_dash and b_job in admin_dash
    assert "only-a" not in world.as_(B).get("/v1/robots").text
    assert "only-a" in world.as_(A).get("/v1/robots").text


def test_a_hand_of_the_same_name_is_each_tenants_own(world: World) -> None:
    assert world.as_(A).get("/v1/robots/shared").json()["dof"] == 1
    assert world.as_(B).get("/v1/robots/shared").json()["dof"] == 2
    for who, dof in ((A, 1), (B, 2)):
        result = world.as_(who).post("/v1/synthesize", json=request_body("shared", max_iterations=1))
        assert result.status_code == 200, result.text
        assert result.json()["timings"]["robot_dof"] == dof  # each job ran on its own tenant's URDF
    refused = world.as_(B).post("/v1/synthesize", json=request_body("only-a", max_iterations=1))
    assert refused.status_code == 404 and "only-a" in refused.json()["error"]


def test_owner_can_cancel(world: World) -> None:
    job_id = world.as_(A).post("/v1/jobs", json=request_body(HAND, max_iterations=500)).json()["id"]
    assert world.as_(A).delete(f"/v1/jobs/{job_id}").status_code == 200
    deadline = time.monotonic() + 30
    while (state := world.as_(A).get(f"/v1/jobs/{job_id}").json()["state"]) in ("queued", "running"):
        assert time.monotonic() < deadline
        time.sleep(0.05)
    assert state == "cancelled"


def test_every_route_with_a_resource_is_in_the_matrix(world: World) -> None:
    """A new route naming a job, batch or robot must be added to `routes` (and so be isolated)."""
    named = {
        (method, path)
        for path, _, methods in route_table(create_app(Settings()))
        for method in methods - {"HEAD"}
        if "{" in path and path.startswith("/v1")
    }
    assert len(named) >= 8  # the table is really read
    covered = {(m, p.replace(world.job, "{job_id}").replace(world.long_job, "{job_id}")
                .replace(world.batch, "{batch_id}").replace("only-a", "{name}")) for m, p in routes(world)}  # fmt: skip
    assert named <= covered, named - covered
