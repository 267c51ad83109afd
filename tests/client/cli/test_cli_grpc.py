"""`mani synthesize --grpc` and `mani jobs show|cancel --grpc` against the real service (HTTP and gRPC on free
ports, the staged test pipeline: ``tests/api/grpc/conftest.py``): the same output as over HTTP."""

from __future__ import annotations

import json
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from manifoundation.cli.main import EXIT_FAILED, EXIT_OK, EXIT_UNREACHABLE, EXIT_USAGE, main
from manifoundation.contract import JobState
from manifoundation.sdk import make_request, object_from_points, save_object
from manifoundation.sdk.grpc_client import GrpcClient
from tests.api.grpc.conftest import HAND, KEY, Service, running
from tests.api.helpers import sphere
from tests.api.server import free_port

REQUEST = ["--hand", HAND, "--method", "direct_grasp", "--max-iterations", "2", "--api-key", KEY, "--json"]


@pytest.fixture(scope="module")
def service(request: pytest.FixtureRequest) -> Iterator[Service]:
    with running(request) as svc:
        yield svc


@pytest.fixture
def object_file(tmp_path: Path) -> Path:
    points, normals = sphere(128)
    return save_object(object_from_points(points, normals, properties={"friction": 0.8}), tmp_path / "ball.npz")


def printed(capsys: pytest.CaptureFixture[str]) -> Any:
    return json.loads(capsys.readouterr().out)


def without_timings(result: dict[str, Any]) -> dict[str, Any]:
    """A result without what differs from run to run (its stages' times; their names stay)."""
    return {**result, "timings": sorted(result["timings"])}


def test_synthesize_over_grpc_prints_and_writes_what_http_does(
    service: Service, object_file: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    outs = {"http": tmp_path / "http.json", "grpc": tmp_path / "grpc.json"}
    transports = {"http": ["--url", service.base], "grpc": ["--grpc", service.target]}
    answers = {}
    for name, transport in transports.items():
        argv = ["synthesize", str(object_file), *REQUEST, *transport, "--out", str(outs[name])]
        assert main(argv) == EXIT_OK, name
        answers[name] = printed(capsys)
    http, grpc = answers["http"], answers["grpc"]
    assert http.keys() == grpc.keys() == {"job_id", "result"} and http["job_id"] != grpc["job_id"]
    assert without_timings(grpc["result"]) == without_timings(http["result"]) and grpc["result"]["hand"] == HAND
    written = {name: json.loads(path.read_text()) for name, path in outs.items()}
    assert without_timings(written["grpc"]) == without_timings(written["http"])
    with GrpcClient(service.target, KEY) as client:  # the gRPC run's job is the service's own
        assert client.job(grpc["job_id"]).status().state is JobState.SUCCEEDED


def test_jobs_show_and_cancel_over_grpc(
    service: Service, object_file: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    points, normals = sphere(128)
    request = make_request(object_from_points(points, normals), robot=HAND, method="direct_grasp", max_iterations=20)
    with GrpcClient(service.target, KEY) as client:
        running_job, done_job = client.submit(request), client.submit(request.model_copy(deep=True))
    grpc, http = ["--grpc", service.target, "--api-key", KEY], ["--url", service.base, "--api-key", KEY]

    assert main(["jobs", "cancel", running_job.id, *grpc, "--json"]) == EXIT_OK
    assert printed(capsys)["id"] == running_job.id  # asked: the worker stops it at its next stage
    assert main(["jobs", "show", running_job.id, "--follow", *grpc, "--json"]) == EXIT_FAILED  # no result
    assert printed(capsys)["state"] == JobState.CANCELLED.value

    out = tmp_path / "r.json"
    assert main(["jobs", "show", done_job.id, "--follow", "--out", str(out), *grpc, "--json"]) == EXIT_OK
    over_grpc = printed(capsys)
    assert main(["jobs", "show", done_job.id, *http, "--json"]) == EXIT_OK
    assert over_grpc == printed(capsys)  # the same job, read over either transport
    assert over_grpc["state"] == "succeeded" and json.loads(out.read_text())["hand"] == HAND

    assert main(["jobs", "show", "no-such-job", *grpc]) == EXIT_USAGE
    nobody = ["--grpc", f"127.0.0.1:{free_port()}", "--retries", "0"]
    assert main(["synthesize", str(object_file), *REQUEST, *nobody]) == EXIT_UNREACHABLE
