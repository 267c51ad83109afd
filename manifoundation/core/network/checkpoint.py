"""Checkpoints: a directory holding ``model.safetensors`` (weights) and ``model_card.json`` (what they are).

The card records the configuration (name and every field), the parameter count, whether the weights were
trained, a training-data summary, metrics, supported materials and the format version. Loading refuses a
checkpoint whose configuration differs from the registered one of the same name (or from the one the caller
expects), or whose tensors do not match the model, and says which fields or tensors differ.
"""

from __future__ import annotations

import dataclasses
import json
import math
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from safetensors.torch import load_file, save_file

from manifoundation.core.errors import CheckpointError
from manifoundation.core.network.config import NetworkConfig, config_with_defaults, get_config
from manifoundation.core.network.model import ManiFoundationNet, count_parameters
from manifoundation.core.network.properties import PROPERTY_NAMES

WEIGHTS_FILE = "model.safetensors"
CARD_FILE = "model_card.json"
FORMAT_VERSION = 1


@dataclass
class ModelCard:
    """What a checkpoint is. ``trained`` is False for randomly initialised weights."""

    config_name: str
    config: dict[str, Any]
    param_count: int
    trained: bool = False
    training_data: dict[str, Any] = field(default_factory=dict)  # e.g. {"examples": 3000, "kinds": [...]}
    metrics: dict[str, float] = field(default_factory=dict)
    materials: list[str] = field(default_factory=list)  # e.g. ["rigid", "cloth", "3d_deformable"]
    property_names: list[str] = field(default_factory=lambda: list(PROPERTY_NAMES))
    version: str = "0.1.0"  # version of the weights
    format_version: int = FORMAT_VERSION
    created: str = field(default_factory=lambda: datetime.now(UTC).isoformat(timespec="seconds"))
    notes: str = ""
    # The latent samples' standard deviation at inference, z ~ N(0, prior_scale² I): a sampling temperature
    # chosen on held-out data for these weights (more distinct contact sets against more flat maps).
    prior_scale: float = 1.0

    @classmethod
    def for_model(cls, model: ManiFoundationNet, **kwargs: Any) -> ModelCard:
        """A card describing ``model``'s configuration and size; other fields from ``kwargs``."""
        return cls(
            config_name=model.config.name,
            config=model.config.to_dict(),
            param_count=count_parameters(model),
            **kwargs,
        )


def config_differences(a: dict[str, Any], b: dict[str, Any]) -> list[str]:
    """Human-readable ``field: a != b`` lines for two config dicts."""
    keys = sorted(set(a) | set(b))
    return [f"{k}: {a.get(k, '<missing>')!r} != {b.get(k, '<missing>')!r}" for k in keys if a.get(k) != b.get(k)]


def save_checkpoint(model: ManiFoundationNet, path: str | Path, card: ModelCard | None = None) -> Path:
    """Write ``model``'s weights and card into directory ``path`` (created if needed).

    Args:
        model: the network.
        path: target directory.
        card: its card; default: :meth:`ModelCard.for_model` with ``trained=False``.

    Returns:
        The directory.
    """
    out = Path(path)
    out.mkdir(parents=True, exist_ok=True)
    card = card or ModelCard.for_model(model)
    if card.config != model.config.to_dict() or card.param_count != count_parameters(model):
        raise CheckpointError("the model card does not describe this model (config or parameter count)")
    tensors = {k: v.detach().cpu().contiguous() for k, v in model.state_dict().items()}
    save_file(tensors, str(out / WEIGHTS_FILE), metadata={"config_name": card.config_name})
    (out / CARD_FILE).write_text(json.dumps(dataclasses.asdict(card), indent=2) + "\n")
    return out


def read_card(path: str | Path) -> ModelCard:
    """The model card of the checkpoint in directory ``path``."""
    card_path = Path(path) / CARD_FILE
    if not card_path.is_file():
        raise CheckpointError(f"no {CARD_FILE} in {path}")
    try:
        data = json.loads(card_path.read_text())
        card = ModelCard(**data)
        checked_prior_scale(card.prior_scale)
    except (json.JSONDecodeError, TypeError, ValueError) as exc:
        raise CheckpointError(f"malformed {card_path}: {exc}") from exc
    return card


def checked_prior_scale(value: object) -> float:
    """``value`` as a prior scale (the latent samples' standard deviation). Raises ValueError unless it is a
    finite number ≥ 0."""
    if isinstance(value, bool) or not isinstance(value, int | float) or not (math.isfinite(value) and value >= 0):
        raise ValueError(f"prior_scale must be a finite number ≥ 0, got {value!r}")
    return float(value)


def load_checkpoint(path: str | Path, config: str | NetworkConfig | None = None) -> tuple[ManiFoundationNet, ModelCard]:
    """Load a checkpoint directory, checking that it matches its (or the expected) configuration.

    Args:
        path: checkpoint directory.
        config: the configuration the caller expects (name or dataclass); default: the registered
            configuration named in the card.

    Returns:
        The model (eval mode, CPU) and its card.

    Raises:
        CheckpointError: missing files, format from the future, config mismatch, or tensors that do not
            match the model (names or shapes).
    """
    card = read_card(path)
    if card.format_version > FORMAT_VERSION:
        raise CheckpointError(f"checkpoint format {card.format_version} is newer than supported {FORMAT_VERSION}")
    if config is None:
        try:
            expected = get_config(card.config_name)
        except KeyError as exc:
            raise CheckpointError(f"checkpoint config {card.config_name!r} is not registered") from exc
    else:
        expected = get_config(config) if isinstance(config, str) else config
    diffs = config_differences(config_with_defaults(card.config), expected.to_dict())
    if diffs:
        raise CheckpointError(
            f"checkpoint {path} was saved with config {card.config_name!r}, which does not match the expected "
            f"config {expected.name!r}: " + "; ".join(diffs)
        )
    weights = Path(path) / WEIGHTS_FILE
    if not weights.is_file():
        raise CheckpointError(f"no {WEIGHTS_FILE} in {path}")
    state = load_file(str(weights))
    model = ManiFoundationNet(expected)
    own = model.state_dict()
    missing, unexpected = sorted(set(own) - set(state)), sorted(set(state) - set(own))
    wrong = [k for k in own if k in state and own[k].shape != state[k].shape]
    if missing or unexpected or wrong:
        raise CheckpointError(
            f"checkpoint {path} does not match config {expected.name!r}: missing {missing[:5]}, "
            f"unexpected {unexpected[:5]}, wrong shape {wrong[:5]}"
        )
    model.load_state_dict(state)
    return model.eval(), card
