"""The training loop of `mani train`: AdamW, warm-up + cosine schedule, Eq. (3), per-epoch validation,
CSV + PNG curves, a checkpoint every epoch, resume.

Run directory layout (``cfg.out``)::

    config.json            the resolved TrainConfig
    metrics.csv            epoch, split, loss, heat, force, kl, lr, seconds
    curves.png             train/val loss curves
    last/                  checkpoint of the latest epoch (model.safetensors + model_card.json)
    best/                  checkpoint with the lowest validation loss
    state.pt               optimizer/scheduler/epoch/RNG state for resume
"""

from __future__ import annotations

import csv
import json
import math
import platform
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import torch

from models.data.dataset import Examples, load_examples, make_batch
from models.network import ManiFoundationNet, ModelCard, create_model, cvae_loss, load_checkpoint, save_checkpoint
from models.training.config import TrainConfig

CSV_FIELDS = ("epoch", "split", "loss", "heat", "force", "kl", "peak", "hit", "lr", "seconds", "examples")


def pick_device(name: str) -> torch.device:
    """``auto`` → cuda when available, else cpu."""
    if name == "auto":
        return torch.device("cuda" if torch.cuda.is_available() else "cpu")
    return torch.device(name)


def lr_factor(step: int, progress: float, warmup: int, min_ratio: float) -> float:
    """Linear warm-up over ``warmup`` steps, then cosine decay to ``min_ratio`` as ``progress`` (fraction of
    the planned epochs done, in [0, 1]) goes to 1. Epoch-based, so the data may grow between epochs."""
    cos = min_ratio + (1 - min_ratio) * 0.5 * (1 + math.cos(math.pi * min(1.0, max(0.0, progress))))
    return cos * min(1.0, (step + 1) / max(warmup, 1))


@dataclass
class TrainResult:
    """Summary of a run."""

    out: Path
    epochs: int
    wall_seconds: float
    final: dict[str, float]
    best_val: float


def data_summary(train: Examples, val: Examples | None) -> dict[str, Any]:
    """Counts for the model card."""

    def counts(ex: Examples) -> dict[str, Any]:
        hands, n = np.unique(ex.hand, return_counts=True)
        return {
            "examples": len(ex),
            "objects": len(np.unique(ex.obj_index)),
            "articulated": int(np.asarray(ex.extra["articulated"]).sum()),
            "hands": {str(h): int(c) for h, c in zip(hands, n, strict=True)},
        }

    out = {"train": counts(train)}
    if val is not None:
        out["val"] = counts(val)
    return out


def _batch_loss(
    model: ManiFoundationNet, b: Any, cfg: TrainConfig, gen: torch.Generator, device: torch.device
) -> dict[str, torch.Tensor]:
    """The loss terms of Eq. (3) on one batch (posterior z; the generator seeds z on the CPU)."""
    res = model(b.obj, b.hand, b.heat, b.force, generator=gen if device.type == "cpu" else None)
    return cvae_loss(
        res,
        b.heat,
        b.force,
        model.config,
        lambda_c=cfg.lambda_c,
        lambda_s=cfg.lambda_s,
        lambda_kl=cfg.lambda_kl,
        heat_contact_weight=cfg.heat_contact_weight,
    )


def evaluate(
    model: ManiFoundationNet, ex: Examples, cfg: TrainConfig, device: torch.device, hand_scale: float
) -> dict[str, float]:
    """Validation figures over ``ex`` in one pass (no augmentation, fixed noise seeds).

    Returns:
        The mean Eq. (3) terms ``loss``, ``heat``, ``force``, ``kl`` (posterior z), and how usable the heatmaps
        are at inference, decoded from one prior sample z ~ N(0, I) as the service does: ``peak``, the mean
        over examples of the highest predicted heat, and ``hit``, the fraction of examples whose highest-heat
        point lies in a ground-truth contact region (ground-truth heat ≥ 0.5).
    """
    model.eval()
    gen = torch.Generator(device="cpu").manual_seed(cfg.seed)
    prior_gen = torch.Generator(device="cpu").manual_seed(cfg.seed + 1)
    sums: dict[str, float] = {"loss": 0.0, "heat": 0.0, "force": 0.0, "kl": 0.0, "peak": 0.0, "hit": 0.0}
    n = 0
    with torch.no_grad():
        for start in range(0, len(ex), cfg.batch_size):
            idx = np.arange(start, min(len(ex), start + cfg.batch_size))
            b = make_batch(ex, idx, hand_scale).to(device)
            terms = _batch_loss(model, b, cfg, gen, device)
            for k in ("loss", "heat", "force", "kl"):
                sums[k] += float(terms[k].detach()) * len(idx)
            enc = model.encode(b.obj, model.encode_hand(b.hand))
            z = torch.randn((len(idx), 1, model.config.latent_dim), generator=prior_gen).to(device)
            heat = model.decode(enc, z)[0][:, 0]  # (B, N)
            sums["peak"] += float(heat.max(dim=1).values.sum())
            sums["hit"] += float((b.heat.gather(1, heat.argmax(dim=1, keepdim=True)) >= 0.5).sum())
            n += len(idx)
    return {k: v / max(n, 1) for k, v in sums.items()}


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


def train(cfg: TrainConfig, resume: bool = False, progress: bool = True) -> TrainResult:
    """Train (or resume) a network as configured; see the module docstring for the outputs."""
    from tqdm import tqdm

    torch.set_num_threads(cfg.threads)
    device = pick_device(cfg.device)
    out = Path(cfg.out)
    out.mkdir(parents=True, exist_ok=True)
    train_ex, val_ex = _load(cfg)
    model = create_model(cfg.network, seed=cfg.seed).to(device)
    hand_scale = model.config.hand_scale_m
    opt = torch.optim.AdamW(model.parameters(), lr=cfg.lr, weight_decay=cfg.weight_decay)
    start_epoch, wall0, best, global_step = 0, 0.0, float("inf"), 0
    csv_path = out / "metrics.csv"
    if resume and (out / "state.pt").is_file():
        loaded, _ = load_checkpoint(out / "last", cfg.network)
        model.load_state_dict(loaded.state_dict())
        state = torch.load(out / "state.pt", map_location="cpu", weights_only=False)
        opt.load_state_dict(state["optimizer"])
        start_epoch, wall0, best = state["epoch"], state["wall_seconds"], state["best_val"]
        global_step = state["step"]
    else:
        with csv_path.open("w", newline="") as fh:
            csv.DictWriter(fh, CSV_FIELDS).writeheader()
    (out / "config.json").write_text(json.dumps(cfg.to_dict(), indent=2))
    summary = data_summary(train_ex, val_ex)
    rng = np.random.default_rng([cfg.seed, start_epoch])
    gen = torch.Generator(device="cpu").manual_seed(cfg.seed + start_epoch)
    t_start = time.perf_counter() - wall0
    final: dict[str, float] = {}
    epoch = start_epoch
    lr = cfg.lr
    for epoch in range(start_epoch + 1, cfg.epochs + 1):
        if cfg.reload_each_epoch and epoch > start_epoch + 1:
            train_ex, val_ex = _load(cfg)
            summary = data_summary(train_ex, val_ex)
        # drop the last partial batch: BatchNorm cannot train on one example, and a tiny batch is a noisy step
        steps_per_epoch = max(1, len(train_ex) // cfg.batch_size)
        model.train()
        t0 = time.perf_counter()
        perm = rng.permutation(len(train_ex))
        sums = {"loss": 0.0, "heat": 0.0, "force": 0.0, "kl": 0.0}
        seen = 0
        bar = tqdm(range(steps_per_epoch), desc=f"epoch {epoch}/{cfg.epochs}", disable=not progress, leave=False)
        for step in bar:
            if cfg.max_minutes is not None and time.perf_counter() - t_start > cfg.max_minutes * 60:
                break  # time budget spent: validate and save what we have
            idx = perm[step * cfg.batch_size : (step + 1) * cfg.batch_size]
            b = make_batch(train_ex, idx, hand_scale, rng if cfg.augment else None).to(device)
            terms = _batch_loss(model, b, cfg, gen, device)
            frac = (epoch - 1 + step / steps_per_epoch) / cfg.epochs
            if cfg.max_minutes is not None:  # a time budget: decay by whichever runs out first
                frac = max(frac, (time.perf_counter() - t_start) / (cfg.max_minutes * 60))
            lr = cfg.lr * lr_factor(global_step, frac, cfg.warmup_steps, cfg.min_lr_ratio)
            for group in opt.param_groups:
                group["lr"] = lr
            global_step += 1
            opt.zero_grad(set_to_none=True)
            terms["loss"].backward()
            torch.nn.utils.clip_grad_norm_(model.parameters(), cfg.grad_clip)
            opt.step()
            for k in sums:
                sums[k] += float(terms[k].detach()) * len(idx)
            seen += len(idx)
            bar.set_postfix(loss=f"{float(terms['loss'].detach()):.4f}", lr=f"{lr:.2e}")
        bar.close()
        if seen == 0:
            break
        train_m = {k: v / seen for k, v in sums.items()}
        rows = [{"split": "train", **train_m, "examples": seen}]
        val_m = evaluate(model, val_ex, cfg, device, hand_scale) if val_ex is not None else None
        if val_m is not None and val_ex is not None:
            rows.append({"split": "val", **val_m, "examples": len(val_ex)})
        secs = time.perf_counter() - t0
        with csv_path.open("a", newline="") as fh:
            w = csv.DictWriter(fh, CSV_FIELDS)
            for r in rows:
                w.writerow({"epoch": epoch, "lr": lr, "seconds": round(secs, 2), **r})
        plot_curves(csv_path, out / "curves.png")
        wall = time.perf_counter() - t_start
        final = {f"train_{k}": v for k, v in train_m.items()}
        if val_m is not None:
            final.update({f"val_{k}": v for k, v in val_m.items()})
        card = _card(model, cfg, summary, epoch, wall, final, device)
        save_checkpoint(model, out / "last", card)
        score = val_m["loss"] if val_m is not None else train_m["loss"]
        if score < best:
            best = score
            save_checkpoint(model, out / "best", card)
        torch.save(
            {
                "optimizer": opt.state_dict(),
                "step": global_step,
                "epoch": epoch,
                "wall_seconds": wall,
                "best_val": best,
            },
            out / "state.pt",
        )
        msg = f"epoch {epoch}: train {train_m['loss']:.4f}"
        if val_m is not None:
            msg += f"  val {val_m['loss']:.4f} (heat {val_m['heat']:.4f}, force {val_m['force']:.4f}"
            msg += f", peak {val_m.get('peak', 0.0):.2f}, hit {val_m.get('hit', 0.0):.2f})"
        print(msg + f"  [{secs:.0f} s]", flush=True)
        if cfg.max_minutes is not None and wall > cfg.max_minutes * 60:
            break
    return TrainResult(out, epoch, time.perf_counter() - t_start, final, best)


def _load(cfg: TrainConfig) -> tuple[Examples, Examples | None]:
    train_ex = load_examples(list(cfg.data), ("train",), limit=cfg.limit)
    try:
        val_ex: Examples | None = load_examples(list(cfg.data), tuple(cfg.val_splits), limit=cfg.val_limit)
    except ValueError:
        val_ex = None
    return train_ex, val_ex


def _card(
    model: torch.nn.Module,
    cfg: TrainConfig,
    summary: dict[str, Any],
    epoch: int,
    wall: float,
    metrics: dict[str, float],
    device: torch.device,
) -> ModelCard:
    return ModelCard.for_model(
        model,  # type: ignore[arg-type]
        trained=True,
        training_data={
            **summary,
            "generator": "models.data (hierarchical grasp sampling, see models/data/__init__.py)",
            "data_dirs": list(cfg.data),
            "training": {
                "epochs": epoch,
                "wall_seconds": round(wall, 1),
                "device": str(device),
                "machine": f"{platform.machine()} {platform.processor() or ''} "
                f"{torch.get_num_threads()} threads".strip(),
                "config": cfg.to_dict(),
            },
        },
        metrics={k: float(v) for k, v in metrics.items()},
        materials=["rigid", "articulated"],
        notes="Trained on rigid and articulated (revolute/prismatic) examples only; requests for deformable "
        "materials are out of its training distribution.",
    )
