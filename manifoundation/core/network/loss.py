"""The training objective of Eq. (3): λ_C·MSE(heatmap) + λ_S·MSE(force map) + λ_KL·KL(φ_q ‖ N(0, I)).

Optionally the heatmap MSE is weighted towards the contact regions: w_j = 1 + α·heat_gt_j, normalised by
mean(w) (α = 0 is the paper's plain MSE). Contacts cover only a few per cent of the points, so with plain MSE a
network that predicts a low, flat heatmap is already close to the optimum and learns the peaks slowly.

With ``heat_loss="bce"`` (ours) the heat term is the same weighting over a binary cross-entropy on the logits,
the target heat read as a per-point probability. The sigmoid then no longer damps the error: MSE through a
sigmoid has the gradient (p − t)·p(1 − p), about 50× weaker at the 0.02 where every point starts than at 0.5, so a
network trained with it sits at a low flat map for many epochs; the cross-entropy's gradient is (p − t). Both
are minimised by the conditional mean of the target, so where the place of the contact is uncertain they still
mark every plausible place, not none.

:func:`set_heat_loss` is ours: a motion can usually be produced by several grasps (`research.data.grasp_sets`), and
a heatmap decoded from a *prior* sample should be one of them, whichever. Each prior sample pays the (weighted)
heat error of the valid grasp nearest it, so no sample is pulled towards the average of several.

:func:`readout_loss` is ours too: the network's estimate of a deformable contact's motion is motion map / heat
(the service's answer moves a contact by the task's own displacement there instead, which measured better:
`manifoundation.core.deformable.answer`), and the MSE of Eq. (3) makes that ratio right only where the predicted
heat is the conditional mean of the label's — with a contact-weighted cross-entropy it is not, and the motions read
back were 0.25-1.5 of the label's (round 13). This term is the error of the read-out itself at the label's contacts.
"""

from __future__ import annotations

import torch
import torch.nn.functional as F

from manifoundation.core.network.config import NetworkConfig
from manifoundation.core.network.selection import HEAT_FLOOR


def kl_to_standard_normal(mu: torch.Tensor, logvar: torch.Tensor) -> torch.Tensor:
    """KL(N(μ, diag σ²) ‖ N(0, I)), summed over latent dims and averaged over the batch."""
    return (0.5 * (mu.square() + logvar.exp() - 1.0 - logvar).sum(dim=-1)).mean()


HEAT_LOSSES = ("mse", "bce")


def cvae_loss(
    out: dict[str, torch.Tensor],
    heat_gt: torch.Tensor,
    force_gt: torch.Tensor,
    config: NetworkConfig,
    *,
    lambda_c: float | None = None,
    lambda_s: float | None = None,
    lambda_kl: float | None = None,
    heat_contact_weight: float = 0.0,
    heat_loss: str = "mse",
    force_contact_weight: float = 0.0,
) -> dict[str, torch.Tensor]:
    """Eq. (3) with the configuration's weights (overridable per call).

    Args:
        out: the model's training output (``heat`` (B, N), ``force`` (B, N, 3), ``mu``, ``logvar``).
        heat_gt: (B, N) ground-truth heatmap.
        force_gt: (B, N, 3) ground-truth force/motion map (normalised units).
        config: supplies the default λ_C, λ_S, λ_KL.
        heat_contact_weight: α of the module docstring (0: unweighted).
        heat_loss: ``"mse"`` (Eq. 3) or ``"bce"`` on ``out["heat_logit"]`` (module docstring).
        force_contact_weight: β, the force map's MSE weighted by 1 + β·heat_gt per point (0: unweighted). The
            map is zero away from the contacts, so unweighted its value at a contact — the one an answer reads —
            is a few per cent of the term.

    Returns:
        ``loss`` (the weighted sum, differentiable) and its terms ``heat``, ``force``, ``kl``.
    """
    lc = config.lambda_c if lambda_c is None else lambda_c
    ls = config.lambda_s if lambda_s is None else lambda_s
    lk = config.lambda_kl if lambda_kl is None else lambda_kl
    if heat_loss == "bce":
        heat = weighted_heat_bce(out["heat_logit"], heat_gt, heat_contact_weight).mean()
    else:
        heat = contact_weighted_mse(out["heat"], heat_gt, heat_gt, heat_contact_weight)
    force = contact_weighted_mse(out["force"], force_gt, heat_gt, force_contact_weight)
    kl = kl_to_standard_normal(out["mu"], out["logvar"])
    return {"loss": lc * heat + ls * force + lk * kl, "heat": heat, "force": force, "kl": kl}


def contact_weighted_mse(pred: torch.Tensor, target: torch.Tensor, heat_gt: torch.Tensor, alpha: float) -> torch.Tensor:
    """MSE with each point weighted by 1 + α·heat_gt, normalised by the weights' mean (α = 0: the plain MSE).

    Args:
        pred, target: (B, N) or (B, N, C). heat_gt: (B, N) ground-truth heat of the same points.
    """
    if alpha <= 0.0:
        return F.mse_loss(pred, target)
    w = 1.0 + alpha * heat_gt.reshape(*heat_gt.shape, *([1] * (pred.dim() - heat_gt.dim())))
    return (w * (pred - target).square()).mean() / w.mean()


def weighted_heat_error(heat: torch.Tensor, target: torch.Tensor, alpha: float) -> torch.Tensor:
    """Per-map weighted MSE over the last axis: mean_j w_j (h_j − t_j)² / mean_j w_j, w = 1 + α t (broadcasting)."""
    w = 1.0 + alpha * target
    return (w * (heat - target).square()).mean(dim=-1) / w.mean(dim=-1)


def weighted_heat_bce(logit: torch.Tensor, target: torch.Tensor, alpha: float) -> torch.Tensor:
    """Per-map weighted cross-entropy over the last axis: mean_j w_j BCE(logit_j, t_j) / mean_j w_j (broadcasting)."""
    w = 1.0 + alpha * target
    logit, target = torch.broadcast_tensors(logit, target)
    bce = F.binary_cross_entropy_with_logits(logit, target, reduction="none")
    return (w * bce).mean(dim=-1) / w.mean(dim=-1)


def set_heat_loss(
    prior_heat: torch.Tensor, set_heat: torch.Tensor, set_valid: torch.Tensor, alpha: float = 0.0,
    heat_loss: str = "mse",
) -> torch.Tensor:  # fmt: skip
    """Mean over prior samples of the heat error to the nearest valid grasp.

    Args:
        prior_heat: (B, K, N) heatmaps decoded from prior samples z ~ N(0, I) (their logits for ``"bce"``).
        set_heat: (B, G, N) heatmaps of each example's valid grasps (padding rows arbitrary).
        set_valid: (B, G) bool, which rows are valid grasps (at least one per example).
        alpha: contact weighting of :func:`weighted_heat_error`.
        heat_loss: ``"mse"`` or ``"bce"``, as in :func:`cvae_loss`.
    """
    error = weighted_heat_bce if heat_loss == "bce" else weighted_heat_error
    err = error(prior_heat.unsqueeze(2), set_heat.unsqueeze(1), alpha)  # (B, K, G)
    err = err.masked_fill(~set_valid.unsqueeze(1), float("inf"))
    return err.min(dim=2).values.mean()


READOUT_CONTACT = 0.5  # label heat from which a point is a contact whose motion is read


def readout_loss(
    heat: torch.Tensor, force: torch.Tensor, heat_gt: torch.Tensor, force_gt: torch.Tensor
) -> torch.Tensor:
    """Squared error of the motion read at the label's contacts: force / max(heat, floor) against the label's
    force_gt / heat_gt, over points with heat_gt ≥ ``READOUT_CONTACT`` (the predicted heat is held fixed: this term
    trains the map to match the heat, not the heat to match the map).

    Args:
        heat: (B, N) or (B, K, N) predicted heat. force: the predicted map, (B, N, 3) or (B, K, N, 3).
        heat_gt: (B, N) label heat. force_gt: (B, N, 3) label map.

    Returns:
        The mean over contact points (and samples) of |read − label|²; zero without a contact point.
    """
    contact = heat_gt >= READOUT_CONTACT
    target = force_gt / heat_gt.clamp_min(READOUT_CONTACT).unsqueeze(-1)
    if heat.dim() == 3:
        contact = contact.unsqueeze(1).expand_as(heat)
        target = target.unsqueeze(1).expand_as(force)
    read = force / heat.detach().clamp_min(HEAT_FLOOR).unsqueeze(-1)
    err = (read - target).square().sum(dim=-1)
    if not bool(contact.any()):
        return err.sum() * 0.0
    return err[contact].mean()
