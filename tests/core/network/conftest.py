"""Fixtures for the network tests: synthetic objects and one shared untrained `cpu` predictor."""

from __future__ import annotations

from collections.abc import Callable, Iterator

import numpy as np
import pytest
import torch

from manifoundation.core.network import ContactPredictor, NetworkInput


def sphere(n: int, radius: float, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """``n`` random points on a sphere and their outward normals."""
    d = rng.standard_normal((n, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    return d * radius, d


MakeInput = Callable[..., NetworkInput]


@pytest.fixture(scope="package", autouse=True)
def one_torch_thread() -> Iterator[None]:
    """Run these tests on one torch thread (restored afterwards).

    The tests check values, not speed; with 2 intra-op threads on a loaded 2-core machine, OpenMP barriers
    made small ops up to 10× slower (measured), one thread keeps the suite well under its time budget.
    """
    before = torch.get_num_threads()
    torch.set_num_threads(1)
    yield
    torch.set_num_threads(before)


@pytest.fixture
def make_input() -> MakeInput:
    """Factory: ``make_input(n, seed=0, hand_key="h0", radius=0.1)`` → a NetworkInput on a sphere."""

    def make(n: int, seed: int = 0, hand_key: str = "h0", radius: float = 0.1) -> NetworkInput:
        rng = np.random.default_rng(seed)
        pts, nrm = sphere(n, radius, rng)
        hrng = np.random.default_rng(abs(hash(hand_key)) % 2**32)
        hp, hn = sphere(256, 0.05, hrng)
        motion = np.tile(rng.standard_normal(3) * 0.02, (n, 1))
        return NetworkInput(
            points=pts + rng.standard_normal(3),
            normals=nrm,
            motion=motion,
            mask=pts[:, 2] > -0.05,
            properties={"friction": 0.5, "density": 500.0},
            hand_points=hp,
            hand_normals=hn,
            hand_key=hand_key,
        )

    return make


@pytest.fixture(scope="session")
def predictor() -> ContactPredictor:
    """An untrained `cpu` predictor (random weights, seed 0)."""
    return ContactPredictor.untrained("cpu", seed=0)
