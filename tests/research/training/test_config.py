"""Training config: YAML + overrides; the schedule."""

from __future__ import annotations

from pathlib import Path

import pytest

from research.training.config import load_config
from research.training.trainer import lr_factor


def test_yaml_and_overrides(tmp_path: Path) -> None:
    p = tmp_path / "c.yaml"
    p.write_text("epochs: 3\nlr: 0.01\ndata: [a, b]\n")
    cfg = load_config(p, ["epochs=5", "data=c", "lambda_kl=0.01", "augment=false"])
    assert cfg.epochs == 5 and cfg.lr == 0.01 and cfg.data == ["c"] and cfg.lambda_kl == 0.01 and not cfg.augment
    with pytest.raises(ValueError, match="unknown"):
        load_config(p, ["nope=1"])
    with pytest.raises(ValueError, match="key=value"):
        load_config(p, ["epochs"])


def test_shipped_config_loads() -> None:
    cfg = load_config(Path(__file__).parents[3] / "research" / "configs" / "train_cpu.yaml")
    assert cfg.network == "cpu"
    dense = load_config(Path(__file__).parents[3] / "research" / "configs" / "train_dense.yaml")
    assert dense.network == "cpu1k" and dense.heat_loss == "bce" and dense.max_set == 32


def test_an_unknown_heat_loss_is_refused_by_name() -> None:
    with pytest.raises(ValueError, match="heat_loss must be one of"):
        load_config(None, ["heat_loss=l1"])


def test_schedule_warms_up_then_decays() -> None:
    assert lr_factor(0, 0.0, 10, 0.05) == pytest.approx(0.1)
    assert lr_factor(100, 0.0, 10, 0.05) == pytest.approx(1.0)
    assert lr_factor(100, 1.0, 10, 0.05) == pytest.approx(0.05)
    assert lr_factor(100, 0.5, 10, 0.05) == pytest.approx(0.525)
