"""One batch's training objective: Eq. (3) on the posterior sample, plus the grasp-set term on prior samples."""

from __future__ import annotations

import torch

from manifoundation.core.network import ManiFoundationNet, cvae_loss
from manifoundation.core.network.loss import readout_loss, set_heat_loss
from research.data.dataset import Batch, Examples
from research.data.prepare import PreparedObjects, prepare_objects
from research.training.config import TrainConfig


def batch_loss(
    model: ManiFoundationNet, b: Batch, cfg: TrainConfig, gen: torch.Generator, device: torch.device
) -> dict[str, torch.Tensor]:
    """The loss terms of Eq. (3) on one batch (posterior z; the generator seeds z on the CPU), plus the grasp-set
    term on ``cfg.prior_samples`` prior samples and the motion read-out term (posterior and prior samples alike)
    when asked."""
    prior_z = None
    if cfg.prior_samples > 0:
        shape = (b.heat.shape[0], cfg.prior_samples, model.config.latent_dim)
        prior_z = torch.randn(shape, generator=gen).to(device)
    res = model(
        b.obj, b.hand, b.heat, b.force, generator=gen if device.type == "cpu" else None, hierarchy=b.hierarchy,
        prior_z=prior_z,
    )  # fmt: skip
    terms = cvae_loss(
        res,
        b.heat,
        b.force,
        model.config,
        lambda_c=cfg.lambda_c,
        lambda_s=cfg.lambda_s,
        lambda_kl=cfg.lambda_kl,
        heat_contact_weight=cfg.heat_contact_weight,
        heat_loss=cfg.heat_loss,
        force_contact_weight=cfg.force_contact_weight,
    )
    if prior_z is not None:
        prior = res["prior_heat_logit"] if cfg.heat_loss == "bce" else res["prior_heat"]
        terms["set"] = set_heat_loss(prior, b.set_heat, b.set_valid, cfg.heat_contact_weight, cfg.heat_loss)
        terms["loss"] = terms["loss"] + cfg.lambda_set * terms["set"]
    if cfg.lambda_readout > 0:
        heat, force = res["heat"].unsqueeze(1), res["force"].unsqueeze(1)
        if prior_z is not None:
            heat, force = torch.cat([heat, res["prior_heat"]], dim=1), torch.cat([force, res["prior_force"]], dim=1)
        terms["readout"] = readout_loss(heat, force, b.heat, b.force)
        terms["loss"] = terms["loss"] + cfg.lambda_readout * terms["readout"]
    return terms


def prepare(ex: Examples | None, model: ManiFoundationNet, cfg: TrainConfig) -> PreparedObjects | None:
    """The per-object subsets and hierarchies of ``ex`` for ``model`` (None: not asked for, or no examples)."""
    return prepare_objects(ex.points, model.config) if ex is not None and cfg.precompute else None
