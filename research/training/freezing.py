"""Training only part of a network: ``train_only`` parameter-name prefixes, everything else frozen.

Why: the shipped rigid weights lose rigid success when all of them are trained on deformables as well (model
card, rounds 8 and 11). Parameters a rigid or articulated request never reaches can be trained without touching
a single rigid answer: the deformable head (``deformable_head.``, manifoundation/core/network/deformable_head.py — what
the shipped weights train) or the property MLPs ψ of the deformable properties (:data:`DEFORMABLE_PROPERTY_MLPS`;
masked mean pooling drops absent properties, and a rigid request carries only friction and density — tried in
round 12, did not learn).

Frozen modules are kept in eval mode during training: BatchNorm in train mode would normalise with the batch's
statistics and update its running ones, and both would change the frozen part's outputs.
"""

from __future__ import annotations

from collections.abc import Sequence

from torch import nn

from manifoundation.core.network.deformable_head import DEFORMABLE_PROPERTIES
from manifoundation.core.network.properties import PROPERTY_NAMES

# The property MLPs ψ a rigid or articulated request never reaches.
DEFORMABLE_PROPERTY_MLPS: tuple[str, ...] = tuple(
    f"properties.mlps.{PROPERTY_NAMES.index(name)}." for name in DEFORMABLE_PROPERTIES
)


def freeze_except(model: nn.Module, prefixes: Sequence[str]) -> list[nn.Parameter]:
    """Set ``requires_grad`` on the parameters whose names start with one of ``prefixes``, clear it elsewhere.

    Returns:
        The trainable parameters (for the optimiser).

    Raises:
        ValueError: a prefix matches no parameter (a typo would otherwise freeze everything silently).
    """
    names = [n for n, _ in model.named_parameters()]
    unmatched = [p for p in prefixes if not any(n.startswith(p) for n in names)]
    if unmatched:
        raise ValueError(f"train_only: {unmatched} match no parameter; names look like {names[:3]}")
    trainable = []
    for name, param in model.named_parameters():
        param.requires_grad_(any(name.startswith(p) for p in prefixes))
        if param.requires_grad:
            trainable.append(param)
    return trainable


def set_train_mode(model: nn.Module, partial: bool) -> None:
    """``model.train()``; when ``partial`` (after :func:`freeze_except`), every module holding no trainable
    parameter, its own or a child's, goes back to eval mode, so it and its BatchNorm statistics stay as loaded."""
    model.train()
    if partial:
        for module in model.modules():
            if not any(p.requires_grad for p in module.parameters()):
                module.eval()
