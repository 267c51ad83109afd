"""What a run starts from and what it records: :func:`initialise_from` (a checkpoint's weights into the run's
network) and :func:`run_card` (the model card saved with every checkpoint)."""

from __future__ import annotations

import platform
from typing import Any

import torch

from manifoundation.core.network import ManiFoundationNet, ModelCard
from research.training.config import TrainConfig
from research.training.sources import RIGID_MATERIALS


def initialise_from(model: ManiFoundationNet, source: ManiFoundationNet) -> None:
    """Copy ``source``'s weights into ``model``: the same configuration, or ``model``'s with a deformable head
    added or changed. A new head keeps its initialisation (zero output, so ``model`` starts as ``source``); a
    head of the same hidden widths but another output (a motion gain added) takes the source head's hidden layers
    and its output rows for the logit and the motion residual, the gain's row starting at zero; one with more
    inputs (the motion frame added) takes the source's first layer with zero weights on the new inputs, so it
    too starts as ``source``.

    Raises:
        ValueError: the configurations differ otherwise.
    """
    head_fields = {"name": "", "deformable_head": [], "deformable_motion_gain": False, "deformable_frame": False,
                   "deformable_frame_slides_only": False}
    mine = {**model.config.to_dict(), **head_fields}
    theirs = {**source.config.to_dict(), **head_fields}
    same_head = source.config.deformable_head == model.config.deformable_head and (
        model.config.deformable_motion_gain or not source.config.deformable_motion_gain
    ) and (model.config.deformable_frame or not source.config.deformable_frame)
    if mine != theirs or (source.config.deformable_head and not same_head):
        raise ValueError(f"init_from: a {source.config.name!r} network cannot start a {model.config.name!r} one")
    state = source.state_dict()
    target = model.state_dict()
    for key in ("deformable_head.out.weight", "deformable_head.out.bias"):
        if key in state and state[key].shape != target[key].shape:  # (Δ logit, Δ motion) → (Δ logit, gain, Δ motion)
            grown = torch.zeros_like(target[key])
            grown[0], grown[-3:] = state[key][0], state[key][1:]
            state[key] = grown
    for key, weight in list(state.items()):  # a head layer with more inputs (the frame's come last): zero on them
        want = target.get(key)
        if key.startswith("deformable_head.") and want is not None and weight.dim() == 2 \
                and weight.shape[0] == want.shape[0] and weight.shape[1] < want.shape[1]:
            grown = torch.zeros_like(want)
            grown[:, : weight.shape[1]] = weight
            state[key] = grown
    missing, unexpected = model.load_state_dict(state, strict=False)
    assert not unexpected and all(k.startswith("deformable_head.") for k in missing), (missing, unexpected)


def run_card(
    model: torch.nn.Module,
    cfg: TrainConfig,
    summary: dict[str, Any],
    epoch: int,
    wall: float,
    metrics: dict[str, float],
    device: torch.device,
    materials: list[str] | None = None,
    init_card: ModelCard | None = None,
) -> ModelCard:
    """The run's card. With ``train_only`` the frozen weights' own record stays on it: ``init_card``'s training
    data, metrics and notes under ``training_data["init_from"]``, and its prior scale (the frozen network's
    answers were tuned at it)."""
    materials = materials or list(RIGID_MATERIALS)
    deformable = [m for m in materials if m not in RIGID_MATERIALS]
    if cfg.train_only:
        trained = ", ".join(cfg.train_only)
        note = (
            f"The weights of {cfg.init_from} with only {trained} trained on ({', '.join(deformable) or 'rigid'}); "
            "every other parameter, BatchNorm statistics included, as loaded, so a request that never reaches the "
            "trained parameters is answered exactly as by those weights."
        )
    elif not deformable:
        note = (
            "Trained on rigid and articulated (revolute/prismatic) examples only; requests for deformable "
            "materials are out of its training distribution."
        )
    elif "rigid" in materials:
        note = f"Trained on rigid and articulated objects and on deformables ({', '.join(deformable)}) in one run."
    else:
        note = (
            f"Trained on deformable examples only ({', '.join(deformable)}); rigid requests are out of its "
            "training distribution."
        )
    frozen_from = init_card if cfg.train_only else None
    inherited: dict[str, Any] = {}
    if frozen_from is not None:
        inherited = {"init_from": {"path": cfg.init_from, "training_data": frozen_from.training_data,
                                   "metrics": frozen_from.metrics, "notes": frozen_from.notes}}  # fmt: skip
    return ModelCard.for_model(
        model,  # type: ignore[arg-type]
        trained=True,
        prior_scale=frozen_from.prior_scale if frozen_from is not None else 1.0,
        training_data={
            **inherited,
            **summary,
            "generator": "research.data (hierarchical grasp sampling, see research/data/__init__.py; labels: each "
            "example's grasp set, research/data/grasp_sets.py)",
            "data_dirs": list(cfg.data),
            "training": {
                "epochs": epoch,
                "wall_seconds": round(wall, 1),
                "device": str(device),
                "machine": f"{platform.machine()} {platform.processor() or ''} "
                f"{torch.get_num_threads()} threads".strip(),
                "config": cfg.to_dict(),
            },
        },
        metrics={k: float(v) for k, v in metrics.items()},
        materials=materials,
        notes=note,
    )
