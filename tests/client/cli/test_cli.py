"""The client-side `mani` commands against the in-process app: output, --json, files written, exit codes."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import httpx
import numpy as np
import pytest

from manifoundation.cli import common
from manifoundation.cli.main import EXIT_FAILED, EXIT_OK, EXIT_UNREACHABLE, EXIT_USAGE, build_parser, main
from manifoundation.contract import SynthesisRequest
from manifoundation.contract.codec import decode_body
from manifoundation.sdk import Client, make_request, object_from_points, save_object
from tests.client.sdk.inprocess import InProcessService
from tests.client.sdk.queues import FAILURE, FOREVER, HAND


@pytest.fixture
def cli(service: InProcessService, monkeypatch: pytest.MonkeyPatch) -> Any:
    def factory(args: Any) -> Client:
        return Client(args.url, args.api_key, encoding=args.encoding, retries=args.retries,
                      transport=service.transport(), sleep=lambda s: None)  # fmt: skip

    monkeypatch.setattr(common, "client_factory", factory)
    monkeypatch.setattr("time.sleep", lambda s: None)
    return main


@pytest.fixture
def object_file(tmp_path: Path, object_points: np.ndarray) -> Path:
    return save_object(object_from_points(object_points), tmp_path / "ball.npz")


def _json(capsys: pytest.CaptureFixture[str]) -> Any:
    return json.loads(capsys.readouterr().out)


def test_every_command_has_help_with_an_example(capsys: pytest.CaptureFixture[str]) -> None:
    for argv in (["synthesize"], ["batch"], ["batch", "submit"], ["batch", "status"], ["jobs"], ["jobs", "show"],
                 ["jobs", "cancel"], ["jobs", "list"]):  # fmt: skip
        with pytest.raises(SystemExit) as info:
            build_parser().parse_args([*argv, "--help"])
        assert info.value.code == 0
        out = capsys.readouterr().out
        assert "example:" in out and "mani " in out.split("example:")[1], argv


def test_synthesize_writes_result_and_view(cli: Any, service: InProcessService, object_file: Path, tmp_path: Path,
                                           capsys: pytest.CaptureFixture[str]) -> None:  # fmt: skip
    service.queue.running_reads = 2
    out, view = tmp_path / "r.json", tmp_path / "r.html"
    code = cli([
        "synthesize", str(object_file), "--hand", HAND, "--task", "delta:0,0,0.05", "--method", "direct_grasp",
        "--seed", "7", "--out", str(out), "--view", str(view), "--json",
    ])  # fmt: skip
    assert code == EXIT_OK
    printed = _json(capsys)
    (job_id,) = service.queue.job_ids()
    assert printed["result"]["hand"] == HAND and printed["job_id"] == job_id
    assert json.loads(out.read_text())["hand"] == HAND
    assert "plotly" in view.read_text()[:100_000].lower()
    sent = service.queue.requests[job_id]
    assert sent.options.seed == 7 and sent.task.kind == "delta_pose" and sent.options.method == "direct_grasp"


def test_synthesize_human_output_and_task_forms(cli: Any, service: InProcessService, object_file: Path, tmp_path: Path,
                                                capsys: pytest.CaptureFixture[str]) -> None:  # fmt: skip
    assert cli(["synthesize", str(object_file), "--hand", HAND]) == EXIT_OK
    assert HAND in capsys.readouterr().out
    np.save(tmp_path / "t.npy", np.load(object_file)["points"] + [0, 0, 0.01])
    for task in ("wrench:0,0,1,0,0,0", f"targets:{tmp_path / 't.npy'}", "delta:0,0,0,0.7071,0,0,0.7071"):
        assert cli(["synthesize", str(object_file), "--hand", HAND, "--task", task, "--json"]) == EXIT_OK, task
        capsys.readouterr()
    kinds = [service.queue.requests[j].task.kind for j in service.queue.job_ids()]
    assert kinds == ["force_closure", "wrench", "target_points", "delta_pose"]


def test_synthesize_exit_codes(cli: Any, service: InProcessService, object_file: Path, tmp_path: Path,
                               capsys: pytest.CaptureFixture[str]) -> None:  # fmt: skip
    assert cli(["synthesize", str(tmp_path / "missing.npz")]) == EXIT_USAGE
    assert cli(["synthesize", str(object_file), "--task", "juggle"]) == EXIT_USAGE
    assert cli(["synthesize", str(object_file), "--seed", "-3", "--json"]) == EXIT_USAGE
    assert _json(capsys)["detail"][0]["field"] == "options.seed"
    assert service.seen == []  # all refused before sending
    assert cli(["synthesize", str(object_file), "--json"]) == EXIT_USAGE  # the default hand, leap: the app's 404
    assert _json(capsys)["detail"][0]["field"] == "robot.name"
    last = service.seen[-1]
    assert SynthesisRequest.model_validate(decode_body(last.content, last.headers["content-type"])).robot.name == "leap"
    service.script += [httpx.ConnectError("refused")] * 4
    assert cli(["synthesize", str(object_file), "--hand", HAND]) == EXIT_UNREACHABLE
    service.queue.error = FAILURE
    assert cli(["synthesize", str(object_file), "--hand", HAND, "--json"]) == EXIT_FAILED
    assert "refinement diverged" in capsys.readouterr().out
    service.queue.error, service.queue.running_reads = None, FOREVER
    assert cli(["synthesize", str(object_file), "--hand", HAND, "--timeout", "0.01", "--json"]) == EXIT_FAILED
    assert _json(capsys)["job_id"] == service.queue.job_ids()[-1]


def test_batch_submit_dir_and_jsonl_then_status(cli: Any, service: InProcessService, object_file: Path,
                                                tmp_path: Path, object_points: np.ndarray,
                                                capsys: pytest.CaptureFixture[str]) -> None:  # fmt: skip
    save_object(object_from_points(object_points * 2), tmp_path / "big.npz")
    assert cli(["batch", "submit", str(tmp_path), "--hand", HAND, "--method", "direct_grasp", "--json"]) == EXIT_OK
    submitted = _json(capsys)
    assert submitted["total"] == 2 and submitted["batches"] == list(service.queue.batches)
    out = tmp_path / "results.jsonl"
    assert cli(["batch", "status", submitted["batches"][0], "--wait", "--out", str(out), "--json"]) == EXIT_OK
    assert _json(capsys)["counts"] == {"succeeded": 2}
    lines = [json.loads(line) for line in out.read_text().splitlines()]
    assert [line["index"] for line in lines] == [0, 1] and all("result" in line for line in lines)

    jsonl = tmp_path / "requests.jsonl"
    jsonl.write_text("\n".join(make_request(object_points, robot=HAND, seed=i).model_dump_json() for i in range(3)))
    service.queue.error = FAILURE
    assert cli(["batch", "submit", str(jsonl), "--wait", "--json"]) == EXIT_FAILED
    assert _json(capsys)["failed"] == 3
    assert cli(["batch", "status", submitted["batches"][0]]) == EXIT_OK
    assert "succeeded 2" in capsys.readouterr().out
    bad = tmp_path / "bad.jsonl"
    bad.write_text('{"object": {}}\n')
    assert cli(["batch", "submit", str(bad)]) == EXIT_USAGE
    assert cli(["batch"]) == EXIT_USAGE
    assert len(service.queue.batches) == 2


def test_jobs_list_show_cancel(cli: Any, service: InProcessService, object_file: Path, tmp_path: Path,
                               capsys: pytest.CaptureFixture[str]) -> None:  # fmt: skip
    service.queue.running_reads = FOREVER
    assert cli(["synthesize", str(object_file), "--hand", HAND, "--timeout", "0.01"]) == EXIT_FAILED
    (held,) = service.queue.job_ids()
    assert cli(["jobs", "--json"]) == EXIT_OK
    assert [j["id"] for j in _json(capsys)] == [held]
    assert cli(["jobs", "list", "--state", "running"]) == EXIT_OK
    assert held in capsys.readouterr().out
    assert cli(["jobs", "cancel", held, "--json"]) == EXIT_OK
    assert _json(capsys)["state"] == "cancelled"
    assert cli(["jobs", "show", held]) == EXIT_FAILED  # ended without a result
    assert cli(["jobs", "show", "nope"]) == EXIT_USAGE
    service.queue.running_reads = None
    assert cli(["synthesize", str(object_file), "--hand", HAND, "--json"]) == EXIT_OK
    capsys.readouterr()
    done = service.queue.job_ids()[-1]
    out = tmp_path / "r.json"
    assert cli(["jobs", "show", done, "--follow", "--out", str(out), "--json"]) == EXIT_OK
    assert _json(capsys)["result_summary"]["success"] and json.loads(out.read_text())["hand"] == HAND


def test_synthesize_request_file_and_inline_urdf(cli: Any, service: InProcessService, object_file: Path,
                                                 tmp_path: Path, object_points: np.ndarray) -> None:  # fmt: skip
    request = tmp_path / "request.json"
    request.write_text(make_request(object_points, "force_closure", HAND, seed=11).model_dump_json())
    assert cli(["synthesize", str(request), "--seed", "99"]) == EXIT_OK  # a whole request is used as it is
    sent = service.queue.requests[service.queue.job_ids()[0]]
    assert sent.robot.name == HAND and sent.options.seed == 11
    urdf = tmp_path / "g.urdf"
    urdf.write_text('<robot name="g"><link name="a"/><link name="b"/></robot>')
    assert cli(["synthesize", str(object_file), "--urdf", str(urdf)]) == EXIT_USAGE  # needs --fingertips
    assert cli(["synthesize", str(object_file), "--urdf", str(urdf), "--fingertips", "a,b"]) == EXIT_OK
    inline = service.queue.requests[service.queue.job_ids()[1]].robot
    assert inline.urdf is not None and inline.fingertips == ["a", "b"] and inline.name is None


def test_batch_jsonl_errors_name_the_line(cli: Any, tmp_path: Path, object_points: np.ndarray,
                                          capsys: pytest.CaptureFixture[str]) -> None:  # fmt: skip
    good = make_request(object_points).model_dump_json()
    bad = good.replace('"force_closure"', '"juggle"')
    (tmp_path / "r.jsonl").write_text(f"{good}\n\n{bad}\n")
    assert cli(["batch", "submit", str(tmp_path / "r.jsonl"), "--json"]) == EXIT_USAGE
    assert _json(capsys)["detail"][0]["field"].startswith("line 3.task")


def test_stop_after_asks_for_stop_after_verified(object_file: Path) -> None:
    from manifoundation.cli.synthesize import build_request

    args = build_parser().parse_args(["synthesize", str(object_file), "--proposals", "4", "--stop-after", "1"])
    assert build_request(args).options.stop_after_verified == 1
    args = build_parser().parse_args(["synthesize", str(object_file), "--proposals", "4"])
    assert build_request(args).options.stop_after_verified is None


def test_corrections_ask_for_rollout_corrections(object_file: Path) -> None:
    from manifoundation.cli.synthesize import build_request

    args = build_parser().parse_args(["synthesize", str(object_file), "--rollout", "--corrections", "4"])
    assert build_request(args).options.rollout_corrections == 4
    args = build_parser().parse_args(["synthesize", str(object_file), "--rollout"])
    assert build_request(args).options.rollout_corrections == 0


def test_the_proposal_table_fits_100_columns_with_the_contact_source(object_points: np.ndarray) -> None:
    """Piped output (not a terminal) is laid out for 100 columns, nothing cut: source, ε and the palm in full."""
    import io

    from rich.console import Console

    from manifoundation.cli.synthesize import result_table
    from tests.api.fakes import fake_result

    request = make_request(object_from_points(object_points), "force_closure", HAND)
    result = fake_result(request)
    best = result.proposals[0].model_copy(update={"contact_source": "random_fallback"})
    result = result.model_copy(update={"proposals": [best, best]})
    out = io.StringIO()
    Console(file=out, width=common.TABLE_WIDTH, color_system=None).print(result_table(result))
    lines = out.getvalue().splitlines()
    assert max(len(line) for line in lines) <= 100
    palm = " ".join(f"{v:+.3f}" for v in best.palm_position)
    assert sum("random_fallback" in line and "0.100" in line and palm in line for line in lines) == 2


def test_simulate_asks_for_the_test_and_the_table_shows_its_verdict(object_file: Path, object_points: np.ndarray
                                                                    ) -> None:  # fmt: skip
    import io

    from rich.console import Console

    from manifoundation.cli.synthesize import build_request, result_table
    from tests.api.fakes import fake_result

    assert build_request(build_parser().parse_args(["synthesize", str(object_file), "--simulate"])).options.simulate
    assert not build_request(build_parser().parse_args(["synthesize", str(object_file)])).options.simulate
    request = make_request(object_from_points(object_points), "force_closure", HAND, simulate=True)
    result = fake_result(request)  # its proposal's test moved the object in +z
    best = result.proposals[0].model_copy(update={"contact_source": "random_fallback"})
    assert best.quality.physics is not None and best.quality.physics.reason == "moved"
    out = io.StringIO()
    Console(file=out, width=common.TABLE_WIDTH, color_system=None).print(result_table(
        result.model_copy(update={"proposals": [best]})))
    lines = out.getvalue().splitlines()
    assert max(len(line) for line in lines) <= 100
    assert any("physics" in line for line in lines) and any("moved" in line and "random_fallback" in line
                                                            for line in lines)  # fmt: skip
