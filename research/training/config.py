"""Training configuration: a YAML file plus ``key=value`` overrides from the command line."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any


@dataclass
class TrainConfig:
    """Everything a training run needs (recorded in the run directory and the model card)."""

    # --- data ---
    data: list[str] = field(default_factory=lambda: ["data/v1"])  # generated data directories
    val_splits: list[str] = field(default_factory=lambda: ["test_so", "test_uo"])
    limit: int | None = None  # cap on training examples (None: all)
    val_limit: int | None = 128  # cap on validation examples (None: all)
    reload_each_epoch: bool = False  # re-read the data directories every epoch (train while generating)
    augment: bool = True  # random rotations
    # --- model ---
    network: str = "cpu"  # registered network configuration
    seed: int = 0
    # --- optimisation (AdamW + linear warm-up then cosine decay) ---
    epochs: int = 20
    batch_size: int = 16
    lr: float = 1e-3
    weight_decay: float = 1e-4
    warmup_steps: int = 50
    min_lr_ratio: float = 0.05
    grad_clip: float = 5.0
    # --- loss of Eq. (3); None: the network configuration's λ ---
    lambda_c: float | None = None
    lambda_s: float | None = None
    lambda_kl: float | None = None
    heat_contact_weight: float = 0.0  # α: heat MSE weighted by 1 + α·heat_gt (0: the paper's plain MSE)
    force_contact_weight: float = 0.0  # β: force/motion map MSE weighted by 1 + β·heat_gt (0: plain MSE)
    heat_loss: str = "mse"  # "mse" (Eq. 3) or "bce": cross-entropy on the logits (manifoundation.core.network.loss)
    prior_samples: int = 0  # K prior samples per example for the grasp-set loss (0: Eq. 3 alone)
    lambda_set: float = 1.0  # weight of the grasp-set loss (manifoundation.core.network.loss.set_heat_loss)
    lambda_readout: float = (
        0.0  # weight of the motion read-out loss (manifoundation.core.network.loss.readout_loss; 0: none)
    )
    max_set: int = 8  # valid grasps per example a batch carries (the data keeps up to grasp_sets.MAX_SET)
    precompute: bool = True  # per-object point subsets and hierarchies computed once (research.data.prepare)
    mask_dropout: float = 0.0  # probability that a training example's partial region mask is replaced by all ones
    init_from: str | None = None  # start from this checkpoint directory's weights (same network configuration)
    # parameter-name prefixes: only these are trained, the rest frozen in eval mode (research.training.freezing)
    train_only: list[str] | None = None
    # --- run ---
    out: str = "runs/cpu"
    device: str = "auto"  # auto: cuda when available, else cpu
    threads: int = 2
    max_minutes: float | None = None  # time budget: the schedule decays by it and training stops when it ends

    def to_dict(self) -> dict[str, Any]:
        return dataclasses.asdict(self)


def _coerce(value: str, current: Any) -> Any:
    import yaml

    parsed = yaml.safe_load(value)
    if isinstance(current, list) and isinstance(parsed, str):
        return [parsed]
    return parsed


def load_config(path: str | Path | None = None, overrides: list[str] | None = None) -> TrainConfig:
    """A config from YAML ``path`` (optional) with ``key=value`` overrides applied.

    Raises:
        ValueError: an unknown key or a malformed override.
    """
    import yaml

    cfg = TrainConfig()
    names = {f.name for f in dataclasses.fields(TrainConfig)}
    data: dict[str, Any] = {}
    if path is not None:
        data = yaml.safe_load(Path(path).read_text()) or {}
    for item in overrides or []:
        if "=" not in item:
            raise ValueError(f"override {item!r} must be key=value")
        k, v = item.split("=", 1)
        data[k.strip()] = _coerce(v, getattr(cfg, k.strip(), None))
    unknown = set(data) - names
    if unknown:
        raise ValueError(f"unknown training settings {sorted(unknown)}; known: {sorted(names)}")
    from manifoundation.core.network.loss import HEAT_LOSSES

    if data.get("heat_loss", cfg.heat_loss) not in HEAT_LOSSES:
        raise ValueError(f"heat_loss must be one of {HEAT_LOSSES}, got {data['heat_loss']!r}")
    return dataclasses.replace(cfg, **data)
