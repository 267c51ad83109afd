"""The network can fit a handful of synthetic examples: the loss of Eq. (3) drops by at least 10×.

Measured: ≈150 Adam steps on 4 examples of 512 points take ≈20-40 s on 2 cores, so the test is marked slow
(run with ``pytest -m slow``).
"""

from __future__ import annotations

import numpy as np
import pytest
import torch

from models.network import PROPERTY_NAMES, ObjectTensors, create_model, cvae_loss

STEPS = 150
DROP_FACTOR = 10.0


def synthetic_batch(b: int, n: int) -> tuple[ObjectTensors, torch.Tensor, torch.Tensor, torch.Tensor]:
    """Spheres with one push direction each; the contact is the blob behind the motion, force along it."""
    rng = np.random.default_rng(0)
    d = rng.standard_normal((b, n, 3))
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    motion_dir = rng.standard_normal((b, 3))
    motion_dir /= np.linalg.norm(motion_dir, axis=-1, keepdims=True)
    contact = -motion_dir  # push from behind
    heat = np.exp(-np.square(np.linalg.norm(d - contact[:, None], axis=-1)) / 0.1)
    force = heat[..., None] * motion_dir[:, None] * 0.5
    xyz = torch.tensor(d * 0.5, dtype=torch.float32)
    obj = ObjectTensors(
        xyz=xyz,
        normals=torch.tensor(d, dtype=torch.float32),
        motion=torch.tensor(np.repeat(motion_dir[:, None] * 0.1, n, axis=1), dtype=torch.float32),
        mask=torch.ones(b, n),
        prop_values=torch.full((b, len(PROPERTY_NAMES)), 0.5),
        prop_mask=torch.tensor([[True, False, False, False, False, False]] * b),
        scale=torch.full((b,), 0.2),
    )
    hand = torch.tensor(rng.standard_normal((b, 128, 6)), dtype=torch.float32)
    return obj, hand, torch.tensor(heat, dtype=torch.float32), torch.tensor(force, dtype=torch.float32)


@pytest.mark.slow
def test_overfit_a_few_examples() -> None:
    torch.manual_seed(0)
    model = create_model("cpu", seed=0).train()
    obj, hand, heat, force = synthetic_batch(4, 512)
    opt = torch.optim.Adam(model.parameters(), lr=2e-3)
    gen = torch.Generator().manual_seed(0)
    losses = []
    for _ in range(STEPS):
        terms = cvae_loss(model(obj, hand, heat, force, generator=gen), heat, force, model.config)
        opt.zero_grad()
        terms["loss"].backward()
        opt.step()
        losses.append(terms["loss"].item())
    first, last = np.mean(losses[:5]), np.mean(losses[-5:])
    assert last * DROP_FACTOR < first, f"loss {first:.4f} → {last:.4f}"
