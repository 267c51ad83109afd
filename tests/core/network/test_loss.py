"""The motion read-out loss (manifoundation.core.network.loss.readout_loss) on hand-computed values."""

from __future__ import annotations

import pytest
import torch


def test_readout_loss_is_the_error_of_motion_over_heat_at_the_label_contacts() -> None:
    from manifoundation.core.network.loss import readout_loss

    m = torch.tensor([0.3, -0.1, 0.2])
    heat_gt = torch.tensor([[1.0, 0.6, 0.0]])
    force_gt = heat_gt.unsqueeze(-1) * m
    heat = torch.tensor([[0.5, 0.2, 0.9]], requires_grad=True)
    exact = heat.detach().unsqueeze(-1) * m  # read back as m at every point
    assert float(readout_loss(heat, exact, heat_gt, force_gt)) == pytest.approx(0.0, abs=1e-12)
    short = (0.5 * exact).requires_grad_(True)  # read back as m / 2 at the two contacts; point 3 is not one
    loss = readout_loss(heat, short, heat_gt, force_gt)
    assert float(loss) == pytest.approx(float((0.5 * m).square().sum()), rel=1e-6)
    loss.backward()
    assert heat.grad is None and short.grad is not None and not short.grad[0, 2].any()
    per_sample = readout_loss(heat.unsqueeze(1).expand(-1, 2, -1), short.detach().unsqueeze(1).expand(-1, 2, -1, -1),
                              heat_gt, force_gt)  # fmt: skip
    assert float(per_sample) == pytest.approx(float(loss), rel=1e-6)
