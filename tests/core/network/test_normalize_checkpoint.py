"""Normalisation round trip; checkpoints: every parameter survives, mismatches are refused."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import torch
from safetensors.torch import load_file

from manifoundation.core.network import (
    CheckpointError,
    ContactPredictor,
    ModelCard,
    Normalizer,
    create_model,
    load_checkpoint,
    save_checkpoint,
)
from manifoundation.core.network.checkpoint import CARD_FILE, WEIGHTS_FILE


def test_normalizer_unit_box_and_inverse() -> None:
    rng = np.random.default_rng(0)
    pts = rng.random((100, 3)) * [0.3, 0.1, 0.05] + [1.0, 2.0, -3.0]
    nz = Normalizer.fit(pts)
    x = nz.points(pts)
    assert np.isclose(np.ptp(x, axis=0).max(), 1.0)
    np.testing.assert_allclose((x.max(0) + x.min(0)) / 2, 0.0, atol=1e-12)
    np.testing.assert_allclose(nz.unpoints(x), pts)
    v = rng.standard_normal((100, 3))
    np.testing.assert_allclose(nz.unvectors(nz.vectors(v)), v)
    with pytest.raises(ValueError, match="degenerate"):
        Normalizer.fit(np.zeros((5, 3)))
    with pytest.raises(ValueError, match="NaN"):
        Normalizer.fit(np.full((5, 3), np.nan))


def test_checkpoint_round_trip_covers_every_parameter(tmp_path: Path) -> None:
    model = create_model("cpu", seed=5)
    card = ModelCard.for_model(model, training_data={"examples": 0}, materials=["rigid"], metrics={"x": 1.0})
    save_checkpoint(model, tmp_path, card)
    stored = load_file(str(tmp_path / WEIGHTS_FILE))
    assert set(stored) == set(model.state_dict())
    for name, _ in model.named_parameters():
        assert name in stored, f"{name} is not saved"
    loaded, card2 = load_checkpoint(tmp_path)
    for (k, v), (k2, v2) in zip(model.state_dict().items(), loaded.state_dict().items(), strict=True):
        assert k == k2 and torch.equal(v, v2)
    assert card2.param_count == card.param_count and card2.materials == ["rigid"] and card2.trained is False
    meta = json.loads((tmp_path / CARD_FILE).read_text())
    assert {"config_name", "param_count", "training_data", "metrics", "materials", "version"} <= set(meta)


def test_predictor_from_checkpoint_matches(tmp_path: Path, make_input) -> None:
    untrained = ContactPredictor.untrained("cpu", seed=3)
    save_checkpoint(untrained.model, tmp_path, untrained.card)
    loaded = ContactPredictor.from_checkpoint(tmp_path)
    inp = [make_input(300)]
    a, b = untrained.predict(inp, num_samples=2, seed=1)[0], loaded.predict(inp, num_samples=2, seed=1)[0]
    np.testing.assert_array_equal(a.heatmaps, b.heatmaps)


def test_mismatching_config_is_refused(tmp_path: Path) -> None:
    save_checkpoint(create_model("cpu"), tmp_path)
    with pytest.raises(CheckpointError, match="does not match the expected config 'paper'"):
        load_checkpoint(tmp_path, "paper")
    card = json.loads((tmp_path / CARD_FILE).read_text())
    card["config"]["latent_dim"] = 32
    (tmp_path / CARD_FILE).write_text(json.dumps(card))
    with pytest.raises(CheckpointError, match="latent_dim: 32 != 64"):
        load_checkpoint(tmp_path)


def test_wrong_tensors_are_refused(tmp_path: Path) -> None:
    save_checkpoint(create_model("cpu"), tmp_path)
    card = json.loads((tmp_path / CARD_FILE).read_text())
    other = tmp_path / "other"
    save_checkpoint(create_model("paper"), other)
    (other / CARD_FILE).write_text(json.dumps(card))  # a cpu card over paper weights
    with pytest.raises(CheckpointError, match="wrong shape"):
        load_checkpoint(other)
    with pytest.raises(CheckpointError, match=r"no model_card\.json"):
        load_checkpoint(tmp_path / "missing")
