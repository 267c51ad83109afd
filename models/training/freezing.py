"""Training only part of a network: ``train_only`` parameter-name prefixes, everything else frozen.

Why: the shipped weights were trained on rigid and articulated objects, and every run that trained all of them on
deformables as well lost rigid success. A rigid request carries only ``friction`` and ``density``, so the property
MLPs ψ of ``stretch``, ``bending``, ``youngs_modulus`` and ``poisson_ratio`` never see it (masked mean pooling
drops absent properties). Training those alone teaches deformables through their properties and leaves every rigid
answer bit for bit as it was.

Frozen modules are kept in eval mode during training: BatchNorm in train mode would normalise with the batch's
statistics and update its running ones, and both would change the frozen part's outputs.
"""

from __future__ import annotations

from collections.abc import Sequence

from torch import nn

# The parameters a rigid or articulated request never reaches (models.network.properties.PROPERTY_NAMES order:
# friction 0, density 1, stretch 2, bending 3, youngs_modulus 4, poisson_ratio 5).
DEFORMABLE_PROPERTY_MLPS: tuple[str, ...] = (
    "properties.mlps.2.",
    "properties.mlps.3.",
    "properties.mlps.4.",
    "properties.mlps.5.",
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


def set_train_mode(model: nn.Module, prefixes: Sequence[str] | None) -> None:
    """``model.train()``; with ``prefixes``, every module holding no trainable parameter goes back to eval mode.

    A module counts as trainable when one of its own or its children's parameters starts with a prefix; the
    others (and their BatchNorm statistics) stay as loaded.
    """
    model.train()
    if not prefixes:
        return
    for name, module in model.named_modules():
        own = [f"{name}.{p}" if name else p for p, _ in module.named_parameters()]
        if not any(n.startswith(tuple(prefixes)) for n in own):
            module.eval()
