"""`mani serve` as a real process: embedded workers, JSON logs with request ids, clean SIGTERM shutdown."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time

import httpx

from .helpers import request_body
from .server import free_port


def test_mani_serve_runs_and_stops_cleanly() -> None:
    port = free_port()
    env = dict(os.environ, MANI_PIPELINE="research.staged_pipeline:StagedPipeline", MANI_LOG_LEVEL="INFO")
    env.pop("MANI_REDIS_URL", None)
    cmd = [sys.executable, "-m", "manifoundation.cli.main", "serve", "--port", str(port), "--workers", "1"]
    proc = subprocess.Popen(cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    base = f"http://127.0.0.1:{port}"
    try:
        deadline = time.monotonic() + 120
        while True:
            assert proc.poll() is None, proc.stderr.read() if proc.stderr else ""
            assert time.monotonic() < deadline, "mani serve never became ready"
            try:
                if httpx.get(f"{base}/readyz", timeout=2).status_code == 200:
                    break
            except httpx.HTTPError:
                pass
            time.sleep(0.2)
        response = httpx.post(
            f"{base}/v1/synthesize", json=request_body("test_gripper"), headers={"X-Request-ID": "cli-test-42"}
        )
        assert response.status_code == 200 and response.headers["x-request-id"] == "cli-test-42"
        job_id = response.headers["x-job-id"]
    finally:
        proc.send_signal(signal.SIGTERM)
        _, stderr = proc.communicate(timeout=60)
    assert proc.returncode in (0, -signal.SIGTERM), stderr[-3000:]  # uvicorn re-raises the signal it caught
    lines = [json.loads(line) for line in stderr.splitlines() if line.startswith("{")]
    submitted = [e for e in lines if e.get("msg") == "job submitted"]
    assert submitted and submitted[0]["request_id"] == "cli-test-42" and submitted[0]["job_id"] == job_id
    access = [e for e in lines if e.get("msg") == "request" and e.get("route") == "/v1/synthesize"]
    assert access and access[0]["status"] == 200 and access[0]["request_id"] == "cli-test-42"
    assert any(e.get("msg") == "service stopped" for e in lines)
