"""The inference API: shapes, ranges, equivariance, determinism, units, caching, validation."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest
import torch

from manifoundation.core.network import ContactPredictor, NetworkInput


@pytest.mark.parametrize("n", [512, 2048, 5000])
@pytest.mark.parametrize("batch", [1, 8])
def test_shapes_ranges_no_nan(predictor: ContactPredictor, make_input, n: int, batch: int) -> None:
    k = 2 if batch == 1 else 1
    inputs = [make_input(n, seed=i) for i in range(batch)]
    outs = predictor.predict(inputs, num_samples=k, seed=0)
    assert len(outs) == batch
    for out in outs:
        assert out.heatmaps.shape == (k, n) and out.force_maps.shape == (k, n, 3)
        assert np.isfinite(out.heatmaps).all() and np.isfinite(out.force_maps).all()
        assert out.heatmaps.min() >= 0.0 and out.heatmaps.max() <= 1.0


@pytest.mark.parametrize("n", [512, 2048, 5000])
def test_permutation_equivariance(predictor: ContactPredictor, make_input, n: int) -> None:
    inp = make_input(n, seed=3)
    perm = np.random.default_rng(1).permutation(n)
    permuted = dataclasses.replace(
        inp, points=inp.points[perm], normals=inp.normals[perm], motion=inp.motion[perm], mask=inp.mask[perm]
    )
    a, b = predictor.predict([inp, permuted], num_samples=2, seed=5)
    np.testing.assert_allclose(a.heatmaps[:, perm], b.heatmaps, atol=1e-4)
    np.testing.assert_allclose(a.force_maps[:, perm], b.force_maps, atol=1e-4)


def test_seed_determinism_and_diversity(predictor: ContactPredictor, make_input) -> None:
    inp = make_input(1024, seed=1)
    a = predictor.predict([inp], num_samples=2, seed=7)[0]
    b = predictor.predict([inp], num_samples=2, seed=7)[0]
    c = predictor.predict([inp], num_samples=2, seed=8)[0]
    np.testing.assert_array_equal(a.heatmaps, b.heatmaps)
    np.testing.assert_array_equal(a.force_maps, b.force_maps)
    assert np.abs(a.heatmaps - c.heatmaps).max() > 1e-4
    # the K samples of one call differ from each other
    assert np.abs(a.heatmaps[0] - a.heatmaps[1]).max() > 1e-4


def test_prior_scale_sets_the_spread_of_the_latent_samples(make_input, tmp_path) -> None:
    """z ~ N(0, s² I): at s = 0 the K samples are one map (the prior's mean); the card's value is loaded."""
    from manifoundation.core.network.checkpoint import CheckpointError, read_card, save_checkpoint

    model = ContactPredictor.untrained("cpu", seed=0)
    inp = make_input(512, seed=3)
    model.prior_scale = 0.0
    still = model.predict([inp], num_samples=3, seed=1)[0]
    np.testing.assert_array_equal(still.heatmaps[0], still.heatmaps[2])
    model.prior_scale = 1.0
    spread = model.predict([inp], num_samples=3, seed=1)[0]
    assert np.abs(spread.heatmaps[0] - spread.heatmaps[2]).max() > 1e-4
    card = dataclasses.replace(model.card, prior_scale=1.5)
    save_checkpoint(model.model, tmp_path / "w", card)
    assert ContactPredictor.from_checkpoint(tmp_path / "w").prior_scale == 1.5
    old = {k: v for k, v in dataclasses.asdict(card).items() if k != "prior_scale"}  # a card from before the field
    (tmp_path / "w" / "model_card.json").write_text(json.dumps(old))
    assert read_card(tmp_path / "w").prior_scale == 1.0
    with pytest.raises(ValueError, match="prior_scale"):
        ContactPredictor(model.model, dataclasses.replace(card, prior_scale=-1.0))
    (tmp_path / "w" / "model_card.json").write_text(json.dumps(old | {"prior_scale": "wide"}))
    with pytest.raises(CheckpointError, match="prior_scale"):
        read_card(tmp_path / "w")


def test_batch_mates_do_not_change_outputs(predictor: ContactPredictor, make_input) -> None:
    inp = make_input(1000, seed=2)
    alone = predictor.predict([inp], num_samples=2, seed=4)[0]
    mixed = predictor.predict([make_input(700, seed=9, hand_key="other"), inp], num_samples=2, seed=[1, 4])[1]
    np.testing.assert_allclose(alone.heatmaps, mixed.heatmaps, atol=1e-5)
    np.testing.assert_allclose(alone.force_maps, mixed.force_maps, atol=1e-5)


def test_outputs_in_request_frame_and_units(make_input) -> None:
    """Translating the object changes nothing; scaling points and motion by 2 doubles the force map.

    The object's size is also a network input (log-scale channel); it is zeroed here so that the network
    is scale-free and only the normalisation is tested.
    """
    pred = ContactPredictor.untrained("cpu", seed=2)
    enc = pred.model.object_encoder
    with torch.no_grad():
        enc.sa[0].lin_f.weight[:, -1] = 0.0  # level-0 input into the first set abstraction
        enc.fp[-1].first.parts[0].weight[:, -1] = 0.0  # level-0 skip into the last feature propagation
    inp = make_input(600, seed=4)
    moved = dataclasses.replace(inp, points=inp.points + np.array([3.0, -2.0, 1.0]))
    big = dataclasses.replace(inp, points=inp.points * 2.0, motion=inp.motion * 2.0)
    base, tr, scaled = pred.predict([inp, moved, big], num_samples=1, seed=0)
    np.testing.assert_allclose(base.heatmaps, tr.heatmaps, atol=1e-4)
    np.testing.assert_allclose(base.force_maps, tr.force_maps, atol=1e-4)
    np.testing.assert_allclose(base.heatmaps, scaled.heatmaps, atol=1e-4)
    np.testing.assert_allclose(2.0 * base.force_maps, scaled.force_maps, atol=1e-4)


def test_hand_encoding_is_cached(predictor: ContactPredictor, make_input) -> None:
    before = predictor.hand_cache_info()
    batch = [make_input(300, hand_key="cache-a"), make_input(300, seed=1, hand_key="cache-a")]
    predictor.predict(batch, num_samples=1)
    info = predictor.hand_cache_info()
    assert (info["hits"] - before["hits"], info["misses"] - before["misses"]) == (1, 1)
    # same key with different arrays is re-encoded, not silently reused
    changed = make_input(300, hand_key="cache-a")
    changed = dataclasses.replace(changed, hand_points=changed.hand_points * 1.5)
    predictor.predict([changed], num_samples=1)
    assert predictor.hand_cache_info()["misses"] - info["misses"] == 1


def test_untrained_is_labelled(predictor: ContactPredictor) -> None:
    assert predictor.is_trained is False
    assert predictor.card.trained is False and "untrained" in predictor.card.notes


@pytest.mark.parametrize(
    ("field", "value", "message"),
    [
        ("points", np.zeros((10, 2)), "points: expected shape"),
        ("normals", np.full((50, 3), np.nan), "normals: contains NaN"),
        ("mask", np.full(50, 2), "mask: must be boolean"),
        ("properties", {"viscosity": 1.0}, "unknown physical properties"),
        ("hand_key", "", "hand_key"),
    ],
)
def test_bad_input_names_the_field(
    predictor: ContactPredictor, make_input, field: str, value: object, message: str
) -> None:
    bad: NetworkInput = dataclasses.replace(make_input(50), **{field: value})
    with pytest.raises(ValueError, match=message):
        predictor.predict([bad])
