"""`mani offline` without Ray: request files of each format through the worker core, one result file each, every
failure recorded with the contract's error type, and a rerun that runs only what is not finished."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from manifoundation.contract import SynthesisResult
from manifoundation.contract.codec import unpack
from manifoundation.server.commands.offline import main
from manifoundation.server.offline.batch import run_batch
from manifoundation.server.offline.synthesis import SynthesisWorker

from .requests import STAGED, request, results, write_requests


def _summary(out: Path) -> dict[str, object]:
    summary: dict[str, object] = json.loads((out / "summary.json").read_text())
    return summary


def test_every_request_is_answered_or_its_error_recorded_and_a_rerun_skips_them(tmp_path: Path) -> None:
    requests, out = tmp_path / "requests", tmp_path / "out"
    ids = write_requests(requests, 8, jsonl_from=5)
    (requests / "broken.json").write_text("{not json")
    invalid = request(0).model_dump_json().replace('"max_iterations":3', '"max_iterations":0')
    (requests / "invalid.json").write_text(invalid)
    with (requests / "many.jsonl").open("a") as f:
        f.write("[1, 2\n")
    argv = [str(requests), "--out", str(out), "--pipeline", STAGED, "--window", "4", "--no-progress"]
    assert main(argv) == 1  # some requests failed
    got = results(out)
    assert set(got) == {*ids, "broken", "invalid", "many-000004"}
    assert all(got[i]["model_version"] == "staged-test" for i in ids)
    assert got["broken"]["type"] == got["many-000004"]["type"] == "BadRequest"
    assert got["invalid"]["type"] == "ValidationError" and got["invalid"]["state"] == "failed"
    assert got["invalid"]["detail"][0]["field"] == "options.max_iterations"  # type: ignore[index]
    assert _summary(out)["counts"] == {"succeeded": 8, "BadRequest": 2, "ValidationError": 1}

    (out / "r0002.msgpack").unlink()
    assert main(argv) == 1
    assert _summary(out) | {"seconds": 0, "items_per_s": 0} == {
        "found": 11, "skipped": 10, "ran": 1, "answered": 1, "seconds": 0, "items_per_s": 0,
        "counts": {"succeeded": 8, "BadRequest": 2, "ValidationError": 1}, "backend": "local x1",
    }  # fmt: skip
    assert results(out) == got


def test_a_crashing_request_is_recorded_as_worker_lost_and_retried_by_the_rerun(tmp_path: Path) -> None:
    requests, out = tmp_path / "requests", tmp_path / "out"
    ids = write_requests(requests, 6)
    crashing = SynthesisWorker(STAGED, {"crash_seed": 3})
    summary = run_batch(requests, out, crashing, workers=2, batch_size=2, progress=False)
    assert summary.counts == {"succeeded": 5, "WorkerLost": 1}
    assert results(out)["r0003"]["type"] == "WorkerLost"
    summary = run_batch(requests, out, SynthesisWorker(STAGED), workers=2, progress=False)
    assert (summary.skipped, summary.ran, summary.counts) == (5, 1, {"succeeded": 6})
    assert set(results(out)) == set(ids)


def test_real_requests_run_through_the_models_pipeline(tmp_path: Path) -> None:
    requests, out = tmp_path / "requests", tmp_path / "out"
    write_requests(requests, 3)
    argv = [str(requests), "--out", str(out), "--pipeline-options", '{"hands": ["panda_gripper"]}', "--no-progress"]
    assert main(argv) == 0
    answers = [SynthesisResult.model_validate(unpack(p.read_bytes())) for p in sorted(out.glob("*.msgpack"))]
    assert len(answers) == 3 and all(a.hand == "panda_gripper" and a.proposals for a in answers)
    palms = {tuple(a.proposals[0].palm_position) for a in answers}
    assert len(palms) == 3  # three seeds, three answers


@pytest.mark.parametrize("argv", [["--pipeline-options", "[1]"], ["--pipeline-options", "{bad"]])
def test_bad_usage_exits_2(tmp_path: Path, argv: list[str]) -> None:
    assert main([str(tmp_path), "--out", str(tmp_path / "out"), *argv]) == 2
    assert main([str(tmp_path / "missing"), "--out", str(tmp_path / "out")]) == 2
