"""The training loop end to end on a tiny generated data set: outputs, metrics, resume."""

from __future__ import annotations

import csv
import json
from pathlib import Path
from typing import Any

import pytest

from manifoundation.core.network import load_checkpoint
from research.data.generate import DataConfig, generate
from research.training.config import TrainConfig
from research.training.trainer import train

DATA = DataConfig(
    objects=2,
    objects_per_shard=1,
    hands=("panda_gripper",),
    held_out_hands=(),
    palms=6,
    grasps_per_job=2,
    examples_per_grasp=8,
    num_points=256,
    test_fraction=0.0,  # both objects train; test_so (unseen motions of train objects) validates
    kinds=("box", "cylinder"),
)


@pytest.fixture(scope="module")
def data_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("data")
    generate(DATA, out, workers=1, progress=False)
    return out


def test_train_writes_curves_checkpoints_and_resumes(data_dir: Path, tmp_path: Path) -> None:
    cfg = TrainConfig(
        data=[str(data_dir)], out=str(tmp_path / "run"), epochs=1, batch_size=2, limit=6, val_limit=4,
        threads=1, warmup_steps=1, heat_contact_weight=4.0,
    )
    first = train(cfg, progress=False)
    run = Path(first.out)
    for name in ("config.json", "metrics.csv", "curves.png", "state.pt", "last/model.safetensors", "best"):
        assert (run / name).exists(), name
    rows = list(csv.DictReader((run / "metrics.csv").open()))
    assert [r["split"] for r in rows] == ["train", "val"]
    val = rows[1]
    assert 0.0 <= float(val["peak"]) <= 1.0 and 0.0 <= float(val["hit"]) <= 1.0
    assert float(rows[0]["examples"]) == 6  # limit 6, batches of 2: nothing dropped
    card = json.loads((run / "last" / "model_card.json").read_text())
    assert card["training_data"]["training"]["config"]["heat_contact_weight"] == 4.0

    import dataclasses

    resumed = train(dataclasses.replace(cfg, epochs=2), resume=True, progress=False)
    rows = list(csv.DictReader((run / "metrics.csv").open()))
    assert resumed.epochs == 2 and [r["epoch"] for r in rows] == ["1", "1", "2", "2"]
    _model, card2 = load_checkpoint(run / "last", "cpu")
    assert card2.training_data["training"]["epochs"] == 2


def test_a_deformable_data_directory_trains_and_its_card_names_its_materials(tmp_path: Path) -> None:
    from research.data.deformable_generate import DeformableDataConfig
    from research.data.deformable_generate import generate as generate_deformable

    data = tmp_path / "d"
    generate_deformable(DeformableDataConfig(materials=("rope", "plasticine"), bodies=2, examples_per_body=2,
                                             test_fraction=0.0), data, progress=False)  # fmt: skip
    cfg = TrainConfig(data=[str(data)], out=str(tmp_path / "run"), network="cpu1k", epochs=1, batch_size=2,
                      threads=1, warmup_steps=1, val_splits=("test_so",))  # fmt: skip
    result = train(cfg, progress=False)
    card = json.loads((Path(result.out) / "last" / "model_card.json").read_text())
    assert card["materials"] == ["plasticine", "rope"]
    counts = card["training_data"]["train"]["materials"]  # seen-motion examples train, the others validate
    assert set(counts) == {"plasticine", "rope"} and sum(counts.values()) == card["training_data"]["train"]["examples"]


def test_rigid_and_deformable_data_train_in_one_run(data_dir: Path, tmp_path: Path) -> None:
    from research.data.deformable_generate import DeformableDataConfig
    from research.data.deformable_generate import generate as generate_deformable

    soft = tmp_path / "soft"
    generate_deformable(DeformableDataConfig(materials=("rope",), bodies=2, examples_per_body=3, test_fraction=0.0),
                        soft, progress=False)  # fmt: skip
    cfg = TrainConfig(data=[str(data_dir), str(soft)], out=str(tmp_path / "run"), network="cpu1k", epochs=1,
                      batch_size=2, limit=6, threads=1, warmup_steps=1, val_limit=4, max_set=4)  # fmt: skip
    result = train(cfg, progress=False)
    card = json.loads((Path(result.out) / "last" / "model_card.json").read_text())
    assert card["materials"] == ["articulated", "rigid", "rope"]
    sources = card["training_data"]["sources"]
    assert set(sources) == {"rigid", "deformable"}
    assert card["training_data"]["train"]["examples"] == sum(s["train"]["examples"] for s in sources.values())
    rows = list(csv.DictReader((Path(result.out) / "metrics.csv").open()))
    splits = [r["split"] for r in rows]
    assert splits == ["train", "val", "val_rigid", "val_deformable"]
    val, per = rows[1], rows[2:]
    # `val` is the example-weighted mean of the two sources' figures
    n = [float(r["examples"]) for r in per]
    assert float(val["examples"]) == sum(n)
    expected = sum(float(r["loss"]) * k for r, k in zip(per, n, strict=True)) / sum(n)
    assert float(val["loss"]) == pytest.approx(expected, rel=1e-6)
    n_open = [float(r["open_examples"]) for r in per]  # the unmasked figures: over the unmasked examples
    expected_open = sum(float(r["hit_open"]) * k for r, k in zip(per, n_open, strict=True)) / max(sum(n_open), 1)
    assert float(val["hit_open"]) == pytest.approx(expected_open, rel=1e-6, abs=1e-12)
    # every training example of both sources was seen once (batches of 2, none partial here)
    rigid_n, soft_n = sources["rigid"]["train"]["examples"], sources["deformable"]["train"]["examples"]
    assert float(rows[0]["examples"]) == 2 * (rigid_n // 2) + 2 * (soft_n // 2)


def test_a_directory_without_generated_data_is_refused_by_name(tmp_path: Path) -> None:
    (tmp_path / "empty").mkdir()
    with pytest.raises(ValueError, match="empty holds no generated data"):
        train(TrainConfig(data=[str(tmp_path / "empty")], out=str(tmp_path / "run")), progress=False)


def test_best_is_chosen_among_epochs_measured_on_the_same_validation_examples(data_dir: Path, tmp_path: Path) -> None:
    """A run whose validation set grows (trained while its data is generated) makes the first epoch measured on
    the larger set the best, whatever its loss: losses on different examples do not compare."""
    import dataclasses

    cfg = TrainConfig(
        data=[str(data_dir)], out=str(tmp_path / "run"), epochs=1, batch_size=2, limit=4, val_limit=1,
        threads=1, warmup_steps=1,
    )
    train(cfg, progress=False)
    run = Path(cfg.out)
    train(dataclasses.replace(cfg, epochs=2, val_limit=4), resume=True, progress=False)
    rows = [r for r in csv.DictReader((run / "metrics.csv").open()) if r["split"] == "val"]
    assert int(rows[0]["examples"]) == 1 < int(rows[1]["examples"])
    _model, best = load_checkpoint(run / "best", "cpu")
    assert best.training_data["training"]["epochs"] == 2


SHIPPED = Path(__file__).resolve().parents[3] / "manifoundation" / "core" / "weights" / "cpu1k"
RIGID = {"friction": 0.6, "density": 700.0}
ROPE = {"friction": 0.6, "youngs_modulus": 3e4, "poisson_ratio": 0.3}


def _rigid_base(out: Path) -> Path:
    """The shipped weights without their deformable head (the round-10 rigid network), saved as a checkpoint."""
    from manifoundation.core.network import ModelCard, create_model, save_checkpoint

    shipped, card = load_checkpoint(SHIPPED)
    base = create_model("cpu1k")
    base.load_state_dict({k: v for k, v in shipped.state_dict().items() if not k.startswith("deformable_head.")})
    card = ModelCard.for_model(base, trained=True, materials=["articulated", "rigid"], prior_scale=card.prior_scale,
                               training_data={"note": "rigid"})  # fmt: skip
    return save_checkpoint(base, out, card)


def _train_only_from_shipped(tmp_path: Path, network: str, train_only: list[str]) -> tuple[Any, Any, Any]:
    """(the rigid base network, the trained one, its card) after two epochs on a tiny rope set training
    ``train_only``."""
    from research.data.deformable_generate import DeformableDataConfig
    from research.data.deformable_generate import generate as generate_deformable

    soft = tmp_path / "soft"
    generate_deformable(DeformableDataConfig(materials=("rope",), bodies=2, examples_per_body=3, test_fraction=0.0),
                        soft, progress=False)  # fmt: skip
    base = _rigid_base(tmp_path / "base")
    cfg = TrainConfig(data=[str(soft)], out=str(tmp_path / "run"), network=network, epochs=2, batch_size=2,
                      threads=1, warmup_steps=1, val_splits=["test_so"], init_from=str(base), lr=1e-2,
                      train_only=train_only)  # fmt: skip
    result = train(cfg, progress=False)
    after, card = load_checkpoint(Path(result.out) / "last", network)
    return load_checkpoint(base, "cpu1k")[0], after, card


def _outputs(model: Any, properties: dict[str, float]) -> Any:
    """Every output (heatmaps and motion maps of 4 prior samples, flattened) for one fixed random object."""
    import torch

    from manifoundation.core.network.model import ObjectTensors
    from manifoundation.core.network.properties import property_tensors

    gen = torch.Generator().manual_seed(0)
    xyz = torch.rand(1, 1024, 3, generator=gen) - 0.5
    normals = torch.nn.functional.normalize(xyz, dim=-1)
    hand = torch.cat([torch.rand(1, 256, 3, generator=gen) - 0.5, normals[:, :256]], dim=-1)
    z = torch.randn(1, 4, model.config.latent_dim, generator=gen)
    values, mask = property_tensors([properties])
    obj = ObjectTensors(xyz, normals, 0.1 * normals, torch.ones(1, 1024), values, mask, torch.tensor([0.1]))
    model.eval()
    with torch.no_grad():
        enc = model.encode(obj, model.encode_hand(hand))
        return torch.cat([t.flatten() for t in model.decode(enc, z)])


def test_train_only_the_deformable_property_mlps_leaves_every_rigid_answer_bit_identical(tmp_path: Path) -> None:
    import torch

    from research.training.freezing import DEFORMABLE_PROPERTY_MLPS

    before, after, card = _train_only_from_shipped(tmp_path, "cpu1k", list(DEFORMABLE_PROPERTY_MLPS))
    old, new = before.state_dict(), after.state_dict()
    changed = {k for k in old if not torch.equal(old[k], new[k])}
    assert changed and all(k.startswith(DEFORMABLE_PROPERTY_MLPS) for k in changed)  # BatchNorm stats too
    assert card.materials == ["articulated", "rigid", "rope"]
    assert "as loaded" in card.notes
    assert torch.equal(_outputs(before, RIGID), _outputs(after, RIGID))
    assert not torch.equal(_outputs(before, ROPE), _outputs(after, ROPE))


def test_a_deformable_head_trained_from_the_shipped_weights_changes_only_deformable_answers(tmp_path: Path) -> None:
    import torch

    before, after, card = _train_only_from_shipped(tmp_path, "cpu1k_deformable", ["deformable_head."])
    old, new = before.state_dict(), after.state_dict()
    assert all(torch.equal(old[k], new[k]) for k in old)  # every shipped tensor as it was
    assert {k.split(".")[0] for k in set(new) - set(old)} == {"deformable_head"}
    assert card.config_name == "cpu1k_deformable" and card.materials == ["articulated", "rigid", "rope"]
    assert card.prior_scale == 1.75 and card.training_data["init_from"]["training_data"] == {"note": "rigid"}
    assert torch.equal(_outputs(before, RIGID), _outputs(after, RIGID))
    assert not torch.equal(_outputs(before, ROPE), _outputs(after, ROPE))


def test_train_only_refuses_a_prefix_that_names_no_parameter() -> None:
    from manifoundation.core.network import create_model
    from research.training.freezing import freeze_except

    with pytest.raises(ValueError, match=r"properties\.mlp\.9"):
        freeze_except(create_model("cpu1k", seed=0), ["properties.mlp.9"])
