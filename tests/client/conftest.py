"""Fixtures of the SDK tests: the real service app in process (`inprocess.py`), sample results and objects.

The SDK is exercised against ``manifoundation.server.api.app.create_app`` over the in-memory `ScriptedQueue`
(``queues.py``), with no server and no socket; ``script`` answers what only a transport can (connection errors, garbage,
scripted 429s). ``test_service_e2e.py`` runs the same app under uvicorn, ``test_embedded_e2e.py`` the real workers.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from typing import Any

import numpy as np
import pytest

from manifoundation.contract import Proposal, Quality, SynthesisResult
from manifoundation.sdk import Client
from tests.client.sdk.inprocess import InProcessService


def sample_result(hand: str = "leap", contacts: int = 4, seed: int = 0) -> SynthesisResult:
    """A plausible result with numpy arrays (what a worker would produce)."""
    rng = np.random.default_rng(seed)
    points = rng.normal(size=(contacts, 3)) * 0.03
    normals = points / np.linalg.norm(points, axis=1, keepdims=True)
    proposal = Proposal(
        contact_points=points,
        contact_normals=normals,
        forces=-normals * 2.0,
        fingertips=[f"tip_{i}" for i in range(contacts)],
        palm_position=np.array([0.0, 0.0, 0.12]),
        palm_quaternion=np.array([1.0, 0.0, 0.0, 0.0]),
        joint_names=[f"j{i}" for i in range(16)],
        joint_values=np.linspace(0, 1, 16),
        quality=Quality(
            success=True,
            converged=True,
            reason="converged",
            iterations=12,
            wrench_residual=1e-8,
            max_tip_distance=0.001,
            penetration_depth=0.0,
            self_collision_depth=0.0,
            epsilon=0.05,
        ),
    )
    return SynthesisResult(hand=hand, model_version="test", proposals=[proposal], timings={"refinement": 0.1})


def sample_object_points(n: int = 256, seed: int = 0) -> np.ndarray:
    """(n, 6) points and outward normals on a 5 cm sphere."""
    rng = np.random.default_rng(seed)
    normals = rng.normal(size=(n, 3))
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    return np.hstack([normals * 0.05, normals])


@pytest.fixture
def result_factory() -> Callable[..., SynthesisResult]:
    return sample_result


@pytest.fixture
def object_points() -> np.ndarray:
    return sample_object_points()


@pytest.fixture
def service() -> Iterator[InProcessService]:
    """The real app over a `ScriptedQueue`, in this process (started by the first transport asked for)."""
    served = InProcessService()
    yield served
    served.close()


@pytest.fixture
def sleeps() -> list[float]:
    return []


@pytest.fixture
def make_client(service: InProcessService, sleeps: list[float]) -> Iterator[Callable[..., Client]]:
    """`Client` factory: through ``service``'s transport, sleeps recorded in ``sleeps`` (none taken)."""
    clients: list[Client] = []

    def make(**kwargs: Any) -> Client:
        kwargs.setdefault("transport", service.transport())
        kwargs.setdefault("sleep", sleeps.append)
        client = Client("http://testserver", **kwargs)
        clients.append(client)
        return client

    yield make
    for client in clients:
        client.close()
