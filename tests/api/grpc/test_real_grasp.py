"""A client built from the proto alone gets a real grasp over gRPC, and the outside check accepts it.

The service runs the real science (`manifoundation.server.worker.models_pipeline.ModelsPipeline`, the Allegro hand)
behind gRPC; the client is a subprocess that knows only the `.proto` file (no SDK, no generated code of ours) and asks
the service to search for grasps that hold in its simulated test (`simulate`); the grasp it gets is judged by the
independent audit (`research.audit`: its own kinematics, the hand's meshes, the object's exact
mesh), which shares no code with the service's verification.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

from manifoundation.server.api.app import create_app
from manifoundation.server.api.settings import Settings
from research.audit import AuditedGrasp, audit_grasp, third_party_objects

from ..server import free_port, serving
from ..workers import start_queue_and_workers
from .test_proto_only_client import PROTO

HAND = "allegro"
LIFT = [0.0, 0.0, 0.05]
CLIENT = """
import json, sys
import grpc
import numpy as np

protos, services = grpc.protos_and_services("manifoundation/v1/manifoundation.proto")
data = np.load(sys.argv[2])
array = lambda a: protos.Array(dtype="float64", shape=a.shape, data=a.astype("<f8").tobytes())
request = protos.SynthesisRequest(
    object=protos.ObjectIn(points=array(data["points"]), normals=array(data["normals"]),
                           properties=protos.PhysicalProperties(friction=0.8)),
    task=protos.TaskIn(delta_pose=protos.DeltaPoseTask(translation=[0, 0, 0.05], rotation=[1, 0, 0, 0])),
    robot=protos.RobotIn(name=sys.argv[3]),
    options=protos.SynthesisOptions(method="random_contacts", num_proposals=2, seed=0, timeout=120, simulate=True),
)
rows = lambda a: np.frombuffer(a.data, dtype=a.dtype).reshape(tuple(a.shape)).tolist()
with grpc.insecure_channel(sys.argv[1]) as channel:
    result = services.ManiFoundationStub(channel).Synthesize(request, timeout=150)
print(json.dumps([{"success": p.quality.success, "contacts": rows(p.contact_points), "forces": rows(p.forces),
                   "fingertips": list(p.fingertips), "palm": list(p.palm_position),
                   "quaternion": list(p.palm_quaternion), "joints": list(p.joint_names),
                   "values": list(p.joint_values)} for p in result.proposals]))
"""


@pytest.fixture(scope="module")
def target(request: pytest.FixtureRequest) -> Iterator[str]:
    """``host:port`` of a gRPC service running the real science for the Allegro hand."""
    pipeline = "manifoundation.server.worker.models_pipeline:ModelsPipeline"
    with start_queue_and_workers(request, pipeline=pipeline, hands=[HAND]) as queue:
        port = free_port()
        app = create_app(Settings(grpc_port=port, sync_wait_max=150), queue=queue, grpc=True)
        with serving(app) as base:
            import httpx

            deadline = time.monotonic() + 240
            while not httpx.get(f"{base}/v1/robots", timeout=10).json()["robots"]:
                assert time.monotonic() < deadline, "no worker published its hands"
                time.sleep(0.5)
            yield f"127.0.0.1:{port}"


@pytest.mark.slow
def test_a_proto_only_client_gets_a_grasp_the_outside_check_accepts(target: str, tmp_path: Path) -> None:
    obj = third_party_objects(max_count=1)[0]
    points, normals = obj.sample(1024, 0)
    np.savez(tmp_path / "object.npz", points=points, normals=normals)
    (tmp_path / "manifoundation/v1").mkdir(parents=True)
    shutil.copy(PROTO, tmp_path / "manifoundation/v1/manifoundation.proto")
    (tmp_path / "client.py").write_text(CLIENT)
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    done = subprocess.run([sys.executable, "client.py", target, "object.npz", HAND], cwd=tmp_path, env=env,
                          capture_output=True, text=True, timeout=200)  # fmt: skip
    assert done.returncode == 0, done.stderr[-3000:]
    proposals = json.loads(done.stdout)
    claimed = [p for p in proposals if p["success"]]
    assert claimed, "the service verified no proposal"
    wrench = np.r_[np.array(LIFT) / np.linalg.norm(LIFT), np.zeros(3)]
    for p in claimed:  # every grasp the service calls verified passes the outside check
        grasp = AuditedGrasp(np.array(p["contacts"]), np.array(p["forces"]), p["fingertips"], np.array(p["palm"]),
                             np.array(p["quaternion"]), p["joints"], np.array(p["values"]))  # fmt: skip
        report = audit_grasp(HAND, grasp, obj.mesh, points, normals, mu=0.8, target_wrench=wrench)
        assert report.passed, report.failures
    # and the check can fail: the same hand 1 cm to the side no longer touches at its contacts
    p = claimed[0]
    moved = AuditedGrasp(np.array(p["contacts"]), np.array(p["forces"]), p["fingertips"],
                         np.array(p["palm"]) + np.array([0.01, 0.0, 0.0]), np.array(p["quaternion"]), p["joints"],
                         np.array(p["values"]))  # fmt: skip
    assert not audit_grasp(HAND, moved, obj.mesh, points, normals, mu=0.8, target_wrench=wrench).passed
