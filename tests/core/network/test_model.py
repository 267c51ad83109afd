"""Configs, the CVAE's parameters and gradients, the loss of Eq. (3)."""

from __future__ import annotations

import math

import numpy as np
import pytest
import torch

from manifoundation.core.network import (
    PROPERTY_NAMES,
    NetworkConfig,
    ObjectTensors,
    count_parameters,
    create_model,
    cvae_loss,
    get_config,
    list_configs,
)
from manifoundation.core.network.loss import kl_to_standard_normal, set_heat_loss
from manifoundation.core.network.properties import PropertyEncoder, property_tensors


def random_batch(b: int, n: int, seed: int = 0) -> tuple[ObjectTensors, torch.Tensor, torch.Tensor, torch.Tensor]:
    g = torch.Generator().manual_seed(seed)
    normals = torch.nn.functional.normalize(torch.randn(b, n, 3, generator=g), dim=-1)
    obj = ObjectTensors(
        xyz=torch.rand(b, n, 3, generator=g) - 0.5,
        normals=normals,
        motion=0.1 * torch.randn(b, n, 3, generator=g),
        mask=(torch.rand(b, n, generator=g) > 0.3).float(),
        prop_values=torch.randn(b, len(PROPERTY_NAMES), generator=g),
        prop_mask=torch.ones(b, len(PROPERTY_NAMES), dtype=torch.bool),
        scale=torch.full((b,), 0.2),
    )
    hand = torch.randn(b, 128, 6, generator=g)
    return obj, hand, torch.rand(b, n, generator=g), 0.1 * torch.randn(b, n, 3, generator=g)


def test_registry() -> None:
    assert {"paper", "cpu"} <= set(list_configs())
    with pytest.raises(KeyError, match="unknown network config 'nope'"):
        create_model("nope")
    for name in list_configs():
        cfg = get_config(name)
        assert NetworkConfig.from_dict(cfg.to_dict()) == cfg


def test_parameter_counts() -> None:
    paper, cpu = count_parameters(create_model("paper")), count_parameters(create_model("cpu"))
    assert 4.5e6 <= paper <= 5.5e6  # "about 5 million parameters"
    assert cpu < paper / 3


def test_create_model_is_seeded() -> None:
    a, b = create_model("cpu", seed=3), create_model("cpu", seed=3)
    for (ka, va), (_, vb) in zip(a.state_dict().items(), b.state_dict().items(), strict=True):
        assert torch.equal(va, vb), ka


def test_training_forward_and_gradients_reach_every_parameter() -> None:
    model = create_model("cpu", seed=0)
    obj, hand, heat, force = random_batch(2, 256)
    out = model(obj, hand, heat, force, generator=torch.Generator().manual_seed(0))
    assert out["heat"].shape == (2, 256) and out["force"].shape == (2, 256, 3)
    assert out["mu"].shape == (2, 64) and out["logvar"].shape == (2, 64)
    loss = cvae_loss(out, heat, force, model.config)["loss"]
    loss.backward()
    for name, p in model.named_parameters():
        assert p.grad is not None, f"no gradient reaches {name}"
        assert torch.isfinite(p.grad).all(), name
        assert p.grad.abs().sum() > 0, f"zero gradient for {name}"


def test_property_encoder_masks_missing_properties() -> None:
    enc = PropertyEncoder()
    values, mask = property_tensors([{"friction": 0.3}, {"friction": 0.3, "youngs_modulus": 1e5}])
    gamma = enc(values, mask)
    assert gamma.shape == (2, 10)
    only_friction = enc.mlps[0](values[:1, :1])
    torch.testing.assert_close(gamma[0], only_friction[0])
    # a missing property's value does not matter
    values2 = values.clone()
    values2[0, 4] = 123.0
    torch.testing.assert_close(enc(values2, mask)[0], gamma[0])
    empty_v, empty_m = property_tensors([{}])
    assert torch.equal(enc(empty_v, empty_m), torch.zeros(1, 10))


def test_loss_weights_and_kl() -> None:
    mu, logvar = torch.zeros(3, 64), torch.zeros(3, 64)
    assert kl_to_standard_normal(mu, logvar).item() == 0.0
    out = {"heat": torch.ones(1, 4), "force": torch.zeros(1, 4, 3), "mu": mu[:1] + 1.0, "logvar": logvar[:1]}
    terms = cvae_loss(out, torch.zeros(1, 4), torch.ones(1, 4, 3), get_config("cpu"), lambda_kl=0.5)
    assert terms["heat"].item() == 1.0 and terms["force"].item() == 1.0 and terms["kl"].item() == 32.0
    assert terms["loss"].item() == pytest.approx(1.0 + 1.0 + 16.0)


def test_contact_weighted_heat_loss() -> None:
    gt = torch.tensor([[1.0, 0.0, 0.0, 0.0]])
    miss_contact = {"heat": torch.tensor([[0.0, 0.0, 0.0, 0.0]]), "force": torch.zeros(1, 4, 3)}
    miss_empty = {"heat": torch.tensor([[1.0, 1.0, 0.0, 0.0]]), "force": torch.zeros(1, 4, 3)}
    for out in (miss_contact, miss_empty):
        out.update(mu=torch.zeros(1, 64), logvar=torch.zeros(1, 64))
    cfg, force = get_config("cpu"), torch.zeros(1, 4, 3)
    # α = 0 is the plain MSE: both errors cost the same
    assert cvae_loss(miss_contact, gt, force, cfg)["heat"].item() == pytest.approx(0.25)
    assert cvae_loss(miss_empty, gt, force, cfg)["heat"].item() == pytest.approx(0.25)
    # α = 4: missing a contact costs 5× an equal error on an empty point (weights normalised by their mean)
    wc = cvae_loss(miss_contact, gt, force, cfg, heat_contact_weight=4.0)["heat"].item()
    we = cvae_loss(miss_empty, gt, force, cfg, heat_contact_weight=4.0)["heat"].item()
    assert wc == pytest.approx(5.0 / 8.0) and we == pytest.approx(1.0 / 8.0)


def test_contact_weighted_force_loss_pays_the_map_at_the_contacts() -> None:
    heat_gt = torch.tensor([[1.0, 0.0, 0.0, 0.0]])
    force_gt = torch.zeros(1, 4, 3)
    force_gt[0, 0] = torch.tensor([0.3, 0.0, 0.0])  # the contact's motion; zero elsewhere, as the labels are
    shrunk = force_gt * 0.2  # the contact's vector at a fifth of its length
    spill = force_gt.clone()
    spill[0, 1] = torch.tensor([0.24, 0.0, 0.0])  # right at the contact, the same error spilt on an empty point
    base = {"heat": heat_gt, "mu": torch.zeros(1, 64), "logvar": torch.zeros(1, 64)}
    cfg = get_config("cpu")
    plain = [cvae_loss({**base, "force": f}, heat_gt, force_gt, cfg)["force"].item() for f in (shrunk, spill)]
    assert plain[0] == pytest.approx(plain[1])  # β = 0: both errors cost the same
    weighted = [cvae_loss({**base, "force": f}, heat_gt, force_gt, cfg, force_contact_weight=4.0)["force"].item()
                for f in (shrunk, spill)]  # fmt: skip
    assert weighted[0] == pytest.approx(5.0 * weighted[1])  # β = 4: the contact's error costs 5×
    assert weighted[0] == pytest.approx(5.0 * 0.24**2 / 12 / (8.0 / 4))


def test_cross_entropy_heat_loss_keeps_its_gradient_where_the_sigmoid_saturates() -> None:
    gt = torch.tensor([[1.0, 0.0, 0.0, 0.0]])
    cfg, force = get_config("cpu"), torch.zeros(1, 4, 3)
    prior = math.log(0.02 / 0.98)
    grads = {}
    for kind in ("mse", "bce"):
        logit = torch.full((1, 4), prior, requires_grad=True)
        out = {"heat": torch.sigmoid(logit), "heat_logit": logit, "force": force, "mu": torch.zeros(1, 64),
               "logvar": torch.zeros(1, 64)}  # fmt: skip
        cvae_loss(out, gt, force, cfg, heat_loss=kind)["heat"].backward()
        assert logit.grad is not None
        grads[kind] = float(logit.grad[0, 0])
    # d/dlogit at p = 0.02 towards a contact (t = 1): MSE (p − t)·p(1 − p)·2/N, cross-entropy (p − t)/N
    assert grads["mse"] == pytest.approx(2 * (0.02 - 1.0) * 0.02 * 0.98 / 4, rel=1e-4)
    assert grads["bce"] == pytest.approx((0.02 - 1.0) / 4, rel=1e-4)
    assert abs(grads["bce"]) > 20 * abs(grads["mse"])


def test_set_heat_loss_with_cross_entropy_pays_the_nearest_valid_grasp() -> None:
    grasps = torch.tensor([[[1.0, 0.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0]]])  # (1, G=2, N=4)
    valid = torch.tensor([[True, True]])
    sure = 8.0
    on_second = torch.tensor([[[-sure, -sure, sure, -sure]]])  # logits of the second grasp
    on_neither = torch.tensor([[[-sure, sure, -sure, -sure]]])
    near = set_heat_loss(on_second, grasps, valid, heat_loss="bce").item()
    far = set_heat_loss(on_neither, grasps, valid, heat_loss="bce").item()
    assert near == pytest.approx(math.log1p(math.exp(-sure)), rel=1e-2)  # the loss of a sure, right logit
    assert far > 3.0


def test_untrained_heatmap_starts_at_the_prior() -> None:
    from manifoundation.core.network.model import HEAT_PRIOR

    model = create_model("cpu", seed=0).eval()
    obj = ObjectTensors(
        xyz=torch.rand(1, 256, 3) - 0.5,
        normals=torch.nn.functional.normalize(torch.randn(1, 256, 3), dim=-1),
        motion=torch.zeros(1, 256, 3),
        mask=torch.ones(1, 256),
        prop_values=torch.zeros(1, 6),
        prop_mask=torch.zeros(1, 6, dtype=torch.bool),
        scale=torch.ones(1),
    )
    with torch.no_grad():
        enc = model.encode(obj, model.encode_hand(torch.randn(1, 64, 6)))
        heat, _ = model.decode(enc, torch.zeros(1, 1, model.config.latent_dim))
    assert 0.2 * HEAT_PRIOR < float(heat.mean()) < 5.0 * HEAT_PRIOR


def test_set_heat_loss_pays_the_nearest_valid_grasp() -> None:
    grasps = torch.tensor([[[1.0, 0.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]]])  # (1, G=3, N=4)
    valid = torch.tensor([[True, True, False]])
    on_second = torch.tensor([[[0.0, 0.0, 1.0, 0.0]]])  # (1, K=1, N): exactly the second valid grasp
    on_padding = torch.tensor([[[0.0, 0.0, 0.0, 1.0]]])  # the third row is padding: not a valid grasp
    average = torch.tensor([[[0.5, 0.0, 0.5, 0.0]]])  # the blur of the two valid ones
    assert set_heat_loss(on_second, grasps, valid).item() == 0.0
    assert set_heat_loss(on_padding, grasps, valid).item() == pytest.approx(0.5)
    assert set_heat_loss(average, grasps, valid).item() == pytest.approx(0.125)
    both = torch.cat([on_second, average], dim=1)  # K = 2: the mean over samples
    assert set_heat_loss(both, grasps, valid).item() == pytest.approx(0.0625)


def test_forward_decodes_prior_samples_on_the_same_encoding() -> None:
    model = create_model("cpu1k", seed=0).eval()
    rng = np.random.default_rng(0)
    n = model.config.num_points
    xyz = torch.as_tensor(rng.uniform(-0.5, 0.5, (2, n, 3)), dtype=torch.float32)
    obj = ObjectTensors(xyz, xyz / xyz.norm(dim=-1, keepdim=True), torch.zeros(2, n, 3), torch.ones(2, n),
                        torch.zeros(2, 6), torch.zeros(2, 6, dtype=torch.bool), torch.full((2,), 0.1))  # fmt: skip
    hand = torch.zeros(2, 16, 6)
    z = torch.randn(2, 3, model.config.latent_dim, generator=torch.Generator().manual_seed(0))
    with torch.no_grad():
        out = model(obj, hand, torch.zeros(2, n), torch.zeros(2, n, 3), prior_z=z)
        enc = model.encode(obj, model.encode_hand(hand))
        heat, _ = model.decode(enc, z)
    assert out["prior_heat"].shape == (2, 3, n) and out["prior_force"].shape == (2, 3, n, 3)
    torch.testing.assert_close(out["prior_heat"], heat)
