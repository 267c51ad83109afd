"""The API under faults and hostile clients: a hung Redis (SIGSTOP) gives 503s within seconds; large bodies do
not stall the event loop; a full queue refuses before a body is read; a slow body is cut off."""

from __future__ import annotations

import contextlib
import gc
import json
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import httpx
import numpy as np

from manifoundation.server.api.app import create_app
from manifoundation.server.api.settings import Settings
from manifoundation.server.queue import create_queue
from tests.worker.redis_server import redis_server

from .helpers import request_body
from .server import serving


def test_hung_redis_gives_503_within_seconds(tmp_path: Path) -> None:
    with redis_server(tmp_path) as server:
        queue = create_queue(server.url, queue_prefix="mani:", redis_timeout=0.5)
        app = create_app(Settings(rate_limit_per_s=0, robots_cache_s=0), queue=queue)
        with serving(app) as base, httpx.Client(base_url=base, timeout=30) as http:
            server.pause()
            try:
                for method, path, body in (
                    ("GET", "/readyz", None),
                    ("POST", "/v1/jobs", request_body("test_gripper")),
                    ("GET", "/v1/jobs", None),
                    ("GET", "/v1/robots", None),
                    ("GET", "/v1/jobs/" + "0" * 32, None),
                ):
                    t0 = time.monotonic()
                    answer = http.request(method, path, json=body)
                    elapsed = time.monotonic() - t0
                    assert answer.status_code == 503, (path, answer.text)
                    assert elapsed < 3.0, (path, elapsed)
                    assert path == "/readyz" or answer.headers["retry-after"]
            finally:
                server.resume()
            assert http.get("/v1/jobs").status_code == 200


def big_body(points: int = 150_000) -> bytes:
    """A valid request of ``points`` points with normals: ≈ 60 bytes a point as JSON."""
    rng = np.random.default_rng(0)
    p = rng.normal(size=(points, 3))
    p /= np.linalg.norm(p, axis=1, keepdims=True)
    body = request_body("test_gripper")
    body["object"] = {"points": (0.04 * p).tolist(), "normals": p.tolist()}
    return json.dumps(body).encode()


def test_large_bodies_do_not_stall_the_event_loop() -> None:
    """Three ≈ 9 MB bodies at once: /healthz keeps answering quickly (they are decoded in worker processes, at
    most two at a time), and all three are accepted."""
    data = big_body()
    queue = create_queue(None, redis_url=None, concurrency=0, max_queue=100)
    app = create_app(Settings(rate_limit_per_s=0), queue=queue)
    with serving(app) as base, httpx.Client(base_url=base, timeout=60) as http:
        answers: list[int] = []

        def post() -> None:
            with httpx.Client(base_url=base, timeout=60) as own:
                answers.append(own.post("/v1/jobs", content=data, headers={"Content-Type": "application/json"})
                               .status_code)  # fmt: skip

        warm_up = [threading.Thread(target=post) for _ in range(2)]  # both decoding children started
        for thread in warm_up:
            thread.start()
        for thread in warm_up:
            thread.join()
        # The test process holds a thousand tests' objects, which no service process does: a full collection
        # of that heap pauses every thread, the server's too (0.66 s once in CI). Frozen, it is not scanned.
        gc.collect()
        gc.freeze()
        try:
            threads = [threading.Thread(target=post) for _ in range(3)]
            for thread in threads:
                thread.start()
            worst = 0.0
            while any(t.is_alive() for t in threads):
                t0 = time.monotonic()
                assert http.get("/healthz").status_code == 200
                worst = max(worst, time.monotonic() - t0)
                time.sleep(0.02)
            for thread in threads:
                thread.join()
        finally:
            gc.unfreeze()
    assert answers == [202] * 5
    assert worst < 0.5, f"/healthz took {worst:.2f} s while large bodies were decoded"


def test_full_queue_refuses_before_reading_the_body() -> None:
    queue = create_queue(None, redis_url=None, concurrency=0, max_queue=1)
    app = create_app(Settings(rate_limit_per_s=0), queue=queue)
    with serving(app) as base, httpx.Client(base_url=base, timeout=60) as http:
        assert http.post("/v1/jobs", json=request_body("test_gripper")).status_code == 202
        with socket.create_connection((base.split("//")[1].split(":")[0], int(base.rsplit(":", 1)[1]))) as sock:
            t0 = time.monotonic()  # a 50 MB body announced, none of it sent: the answer comes at once
            sock.sendall(b"POST /v1/jobs HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\n"
                         b"Content-Length: 50000000\r\n\r\n")  # fmt: skip
            sock.settimeout(5)
            head = sock.recv(4096)
            assert head.startswith(b"HTTP/1.1 429") and b"retry-after" in head.lower(), head
            assert time.monotonic() - t0 < 1.0


def test_a_full_queue_is_refused_after_the_key_check() -> None:
    """The refusal comes first among the route's own work, but a wrong key is still 401, not 429."""
    from fastapi.testclient import TestClient

    key = "secret-key-1234"
    queue = create_queue(None, redis_url=None, concurrency=0, max_queue=1)
    with TestClient(create_app(Settings(api_keys=[key], rate_limit_per_s=0), queue=queue)) as client:
        body, auth = request_body("test_gripper"), {"Authorization": f"Bearer {key}"}
        assert client.post("/v1/jobs", json=body, headers=auth).status_code == 202
        assert client.post("/v1/jobs", json=body).status_code == 401
        for path in ("/v1/jobs", "/v1/synthesize"):
            answer = client.post(path, json=body, headers=auth)
            assert answer.status_code == 429 and answer.json()["type"] == "QueueFull", answer.text
        assert client.post("/v1/batches", json={"requests": [body]}, headers=auth).status_code == 429
        assert client.post("/v1/plans", json={}, headers=auth).status_code == 429  # refused before the body is read


def test_a_slow_body_is_cut_off() -> None:
    """One byte now and then never holds a request open: 408 after the idle (and total) body timeout."""
    queue = create_queue(None, redis_url=None, concurrency=0, max_queue=10)
    app = create_app(Settings(rate_limit_per_s=0, body_idle_timeout=0.5, body_timeout=2), queue=queue)
    with serving(app) as base:
        host, port = base.split("//")[1].split(":")
        for pause in (0.8, 0.3):  # idle past 0.5 s; then one byte every 0.3 s, past the 2 s total
            with socket.create_connection((host, int(port))) as sock:
                sock.sendall(b"POST /v1/jobs HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\n"
                             b"Content-Length: 1000\r\n\r\n{")  # fmt: skip
                sock.settimeout(0.05)
                t0, head = time.monotonic(), b""
                while not head and time.monotonic() - t0 < 5:
                    time.sleep(pause)
                    with contextlib.suppress(OSError):
                        sock.sendall(b" ")
                    with contextlib.suppress(TimeoutError):
                        head = sock.recv(4096)
                assert head.startswith(b"HTTP/1.1 408"), (pause, head)


def test_a_batch_larger_than_the_queue_is_422_not_429_for_ever() -> None:
    queue = create_queue(None, redis_url=None, concurrency=0, max_queue=3)
    with serving(create_app(Settings(rate_limit_per_s=0), queue=queue)) as base:
        answer = httpx.post(f"{base}/v1/batches", json={"requests": [request_body("test_gripper")] * 4}, timeout=30)
        assert answer.status_code == 422 and "at most 3 jobs" in answer.json()["error"], answer.text
        fits = httpx.post(f"{base}/v1/batches", json={"requests": [request_body("test_gripper")] * 3}, timeout=30)
        assert fits.status_code == 202, fits.text


def test_large_bodies_work_from_a_script_without_a_main_guard(tmp_path: Path) -> None:
    """The decoding children are plain `python -m manifoundation.server.api.body_child` processes: a script embedding
    the app
    is never re-imported in them (multiprocessing's spawn would run such a script again)."""
    script = tmp_path / "embed.py"
    script.write_text(
        "import json, sys\n"
        f"sys.path[:0] = [{str(Path(__file__).resolve().parents[2])!r}]\n"
        "from fastapi.testclient import TestClient\n"
        "from manifoundation.server.api.app import create_app\n"
        "from manifoundation.server.api.settings import Settings\n"
        "from tests.api.fakes import FakeQueue\n"
        "from tests.api.test_faults import big_body\n"
        "with TestClient(create_app(Settings(parse_offload_bytes=1024), queue=FakeQueue())) as c:\n"
        "    body = json.loads(big_body(2000)); body['robot']['name'] = 'fake_hand'\n"
        "    r = c.post('/v1/jobs', content=json.dumps(body), headers={'Content-Type': 'application/json'})\n"
        "    print('STATUS', r.status_code)\n"
    )
    out = subprocess.run([sys.executable, str(script)], capture_output=True, text=True, timeout=120)
    assert out.stdout.count("STATUS 202") == 1, out.stdout + out.stderr
