"""A client built from the proto file alone (no SDK, no generated code of ours, no `service` package) works."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

from .conftest import KEY, Service

PROTO = Path(__file__).resolve().parents[3] / "manifoundation/contract/protos/v1/manifoundation.proto"

CLIENT = """
import sys
import grpc
import numpy as np

protos, services = grpc.protos_and_services("manifoundation/v1/manifoundation.proto")
n = 256
i = np.arange(n) + 0.5
phi, theta = np.arccos(1 - 2 * i / n), np.pi * (1 + 5**0.5) * i
normals = np.stack([np.cos(theta) * np.sin(phi), np.sin(theta) * np.sin(phi), np.cos(phi)], axis=1)
points = (0.04 * normals).astype("<f4")
array = lambda a: protos.Array(dtype=str(a.dtype).replace("<f4", "float32"), shape=a.shape, data=a.tobytes())
request = protos.SynthesisRequest(
    object=protos.ObjectIn(points=array(points), normals=array(normals.astype("<f4")),
                           properties=protos.PhysicalProperties(friction=0.8)),
    task=protos.TaskIn(force_closure=protos.ForceClosureTask()),
    robot=protos.RobotIn(name="test_gripper"),
    options=protos.SynthesisOptions(method="direct_grasp", max_iterations=2),
)
with grpc.insecure_channel(sys.argv[1]) as channel:
    stub = services.ManiFoundationStub(channel)
    result = stub.Synthesize(request, metadata=[("authorization", "Bearer " + sys.argv[2])], timeout=30)
print(result.hand, result.model_version, sorted(result.timings))
"""


def test_a_client_from_the_proto_alone(service: Service, tmp_path: Path) -> None:
    (tmp_path / "manifoundation/v1").mkdir(parents=True)
    shutil.copy(PROTO, tmp_path / "manifoundation/v1/manifoundation.proto")
    (tmp_path / "client.py").write_text(CLIENT)
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    done = subprocess.run(
        [sys.executable, "client.py", service.target, KEY], cwd=tmp_path, env=env, capture_output=True, text=True,
        timeout=60,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr[-3000:]
    hand, version, stages = done.stdout.split(" ", 2)
    assert (hand, version) == ("test_gripper", "staged-test") and "refinement" in stages
