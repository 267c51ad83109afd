"""A run's starting weights: the same network, or the same with a deformable head added — nothing else."""

from __future__ import annotations

import pytest
import torch

from manifoundation.core.network import create_model
from research.training.card import initialise_from


def test_a_network_starts_a_copy_of_itself_with_a_deformable_head() -> None:
    source, headed = create_model("cpu1k", seed=0), create_model("cpu1k_deformable", seed=1)
    initialise_from(headed, source)
    theirs, mine = source.state_dict(), headed.state_dict()
    assert all(torch.equal(theirs[k], mine[k]) for k in theirs)


def test_a_head_grows_a_motion_gain_that_starts_at_zero() -> None:
    source, gained = create_model("cpu1k_deformable", seed=0), create_model("cpu1k_deformable_gain", seed=1)
    with torch.no_grad():
        source.deformable_head.out.weight.normal_()  # type: ignore[union-attr]
        source.deformable_head.out.bias.normal_()  # type: ignore[union-attr]
    initialise_from(gained, source)
    theirs, mine = source.state_dict(), gained.state_dict()
    assert all(torch.equal(theirs[k], mine[k]) for k in theirs if not k.startswith("deformable_head.out."))
    for key in ("deformable_head.out.weight", "deformable_head.out.bias"):
        assert torch.equal(mine[key][0], theirs[key][0]) and torch.equal(mine[key][2:], theirs[key][1:])
        assert not mine[key][1].any()  # the gain's row: the grown network answers as its source did


@pytest.mark.parametrize(
    ("source", "target"),
    [("cpu1k_deformable", "cpu1k"), ("cpu", "cpu1k"), ("cpu1k_deformable_gain", "cpu1k_deformable"),
     ("cpu1k_deformable_frame", "cpu1k_deformable_gain"), ("cpu1k_deformable_slide_frame", "cpu1k_deformable_gain")],
)
def test_other_networks_are_refused_by_name(source: str, target: str) -> None:
    with pytest.raises(ValueError, match=f"a '{source}' network cannot start a '{target}' one"):
        initialise_from(create_model(target, seed=0), create_model(source, seed=0))
