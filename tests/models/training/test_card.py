"""A run's starting weights: the same network, or the same with a deformable head added — nothing else."""

from __future__ import annotations

import pytest
import torch

from models.network import create_model
from models.training.card import initialise_from


def test_a_network_starts_a_copy_of_itself_with_a_deformable_head() -> None:
    source, headed = create_model("cpu1k", seed=0), create_model("cpu1k_deformable", seed=1)
    initialise_from(headed, source)
    theirs, mine = source.state_dict(), headed.state_dict()
    assert all(torch.equal(theirs[k], mine[k]) for k in theirs)


@pytest.mark.parametrize(("source", "target"), [("cpu1k_deformable", "cpu1k"), ("cpu", "cpu1k")])
def test_other_networks_are_refused_by_name(source: str, target: str) -> None:
    with pytest.raises(ValueError, match=f"a '{source}' network cannot start a '{target}' one"):
        initialise_from(create_model(target, seed=0), create_model(source, seed=0))
