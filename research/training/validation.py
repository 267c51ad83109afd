"""Validation figures of a training run (per epoch, into metrics.csv) and its loss curves."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
import torch

from manifoundation.core.network import ManiFoundationNet
from research.data.dataset import Examples, make_batch
from research.data.grasp_sets import REGION_HEAT
from research.data.prepare import PreparedObjects
from research.training.config import TrainConfig
from research.training.objective import batch_loss

FLAT_CONTRAST = 0.1  # a heatmap whose peak stands less than this above its median is flat (selection's rule)


def evaluate(
    model: ManiFoundationNet,
    ex: Examples,
    cfg: TrainConfig,
    device: torch.device,
    hand_scale: float,
    prepared: PreparedObjects | None = None,
) -> dict[str, float]:
    """Validation figures over ``ex`` in one pass (no augmentation, fixed noise seeds).

    Returns:
        The mean Eq. (3) terms ``loss``, ``heat``, ``force``, ``kl`` (posterior z), and how usable the heatmaps
        are at inference, decoded from one prior sample z ~ N(0, I) as the service does: ``peak``, the mean
        over examples of the highest predicted heat, ``hit``, the fraction of examples whose highest-heat
        point lies in the contact region (ground-truth heat ≥ 0.5) of any valid grasp of the example, and
        ``flat``, the fraction whose peak stands less than :data:`FLAT_CONTRAST` above the median; ``hit_open``
        and ``flat_open`` the same over the examples without a partial region mask (the mask alone tells a
        network where the label's contacts are: these are the figures that say it has learnt more), and
        ``open_examples`` their count.
    """
    model.eval()
    gen = torch.Generator(device="cpu").manual_seed(cfg.seed)
    prior_gen = torch.Generator(device="cpu").manual_seed(cfg.seed + 1)
    sums = dict.fromkeys(("loss", "heat", "force", "kl", "set", "peak", "hit", "flat", "hit_open", "flat_open"), 0.0)
    n = n_open = 0
    with torch.no_grad():
        for start in range(0, len(ex), cfg.batch_size):
            idx = np.arange(start, min(len(ex), start + cfg.batch_size))
            b = make_batch(ex, idx, hand_scale, prepared=prepared, max_set=cfg.max_set).to(device)
            terms = batch_loss(model, b, cfg, gen, device)
            for k in ("loss", "heat", "force", "kl", "set"):
                sums[k] += float(terms[k].detach()) * len(idx) if k in terms else 0.0
            enc = model.encode(b.obj, model.encode_hand(b.hand), b.hierarchy)
            z = torch.randn((len(idx), 1, model.config.latent_dim), generator=prior_gen).to(device)
            heat = model.decode(enc, z)[0][:, 0]  # (B, N)
            union = b.set_heat.masked_fill(~b.set_valid.unsqueeze(-1), 0.0).amax(dim=1)  # (B, N)
            sums["peak"] += float(heat.max(dim=1).values.sum())
            hit = union.gather(1, heat.argmax(dim=1, keepdim=True))[:, 0] >= REGION_HEAT
            flat = heat.max(dim=1).values - heat.median(dim=1).values < FLAT_CONTRAST
            open_ = (b.obj.mask > 0.5).all(dim=1)
            sums["hit"] += float(hit.sum())
            sums["flat"] += float(flat.sum())
            sums["hit_open"] += float((hit & open_).sum())
            sums["flat_open"] += float((flat & open_).sum())
            n += len(idx)
            n_open += int(open_.sum())
    out = {k: v / max(n, 1) for k, v in sums.items()}
    out.update(hit_open=sums["hit_open"] / max(n_open, 1), flat_open=sums["flat_open"] / max(n_open, 1))
    out["open_examples"] = float(n_open)
    return out


def plot_curves(csv_path: Path, png_path: Path) -> None:
    """Loss curves (train and val, total and terms) from metrics.csv."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows = list(csv.DictReader(csv_path.open()))
    keys = ("loss", "heat", "force", "kl", "hit")
    fig, axes = plt.subplots(1, len(keys), figsize=(20, 3.5))
    for ax, key in zip(axes, keys, strict=True):
        for split in ("train", "val"):
            pts = [(int(r["epoch"]), float(r[key])) for r in rows if r["split"] == split and r.get(key)]
            if pts:
                ax.plot(*zip(*pts, strict=True), marker="o", label=split)
        ax.set_title("val: top-heat point in a true contact region" if key == "hit" else key)
        ax.set_xlabel("epoch")
        ax.set_yscale("linear" if key == "hit" else "log")
        ax.legend()
    fig.tight_layout()
    fig.savefig(png_path, dpi=80)
    plt.close(fig)
