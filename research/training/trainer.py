"""The training loop of `mani-lab train`: AdamW, warm-up + cosine schedule, Eq. (3), per-epoch validation,
CSV + PNG curves, a checkpoint every epoch, resume.

Run directory layout (``cfg.out``)::

    config.json            the resolved TrainConfig
    metrics.csv            epoch, split, loss terms, validation figures (peak, hit, flat), lr, seconds; with
                           rigid and deformable data, ``val`` over both and ``val_rigid`` / ``val_deformable``
    curves.png             train/val loss curves
    last/                  checkpoint of the latest epoch (model.safetensors + model_card.json)
    best/                  checkpoint with the lowest validation loss (among the epochs measured on the same
                           validation examples: with ``reload_each_epoch`` the set grows with the data)
    state.pt               optimizer/scheduler/epoch/RNG state for resume
"""

from __future__ import annotations

import csv
import json
import math
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import torch

from manifoundation.core.network import ManiFoundationNet, ModelCard, create_model, load_checkpoint, save_checkpoint
from research.data.dataset import make_batch
from research.data.prepare import PreparedObjects
from research.training.best import is_best, validation_fingerprint
from research.training.card import initialise_from, run_card
from research.training.config import TrainConfig
from research.training.freezing import freeze_except, set_train_mode
from research.training.objective import batch_loss, prepare
from research.training.sources import (
    Source,
    data_summary,
    epoch_batches,
    load_deformable,
    load_rigid,
    split_dirs,
)
from research.training.validation import evaluate, plot_curves

Prepared = tuple[PreparedObjects | None, PreparedObjects | None]  # a source's (train, val) precomputation

CSV_FIELDS = (
    "epoch", "split", "loss", "heat", "force", "kl", "set", "peak", "hit", "flat", "hit_open", "flat_open", "lr",
    "seconds", "examples", "open_examples",
)  # fmt: skip


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


def train(cfg: TrainConfig, resume: bool = False, progress: bool = True) -> TrainResult:
    """Train (or resume) a network as configured; see the module docstring for the outputs."""
    from tqdm import tqdm

    torch.set_num_threads(cfg.threads)
    device = pick_device(cfg.device)
    out = Path(cfg.out)
    out.mkdir(parents=True, exist_ok=True)
    sources = _load(cfg)
    model = create_model(cfg.network, seed=cfg.seed).to(device)
    init_card: ModelCard | None = None  # what init_from's weights already know stays on the run's card
    if cfg.init_from is not None:
        loaded_init, init_card = load_checkpoint(cfg.init_from)
        if not resume:
            initialise_from(model, loaded_init)
    preps = _prepare(sources, model, cfg)
    hand_scale = model.config.hand_scale_m
    params = freeze_except(model, cfg.train_only) if cfg.train_only else list(model.parameters())
    opt = torch.optim.AdamW(params, lr=cfg.lr, weight_decay=cfg.weight_decay)
    start_epoch, wall0, best, global_step = 0, 0.0, float("inf"), 0
    best_on = ""  # the validation examples `best` was measured on (`validation_fingerprint`)
    csv_path = out / "metrics.csv"
    if resume and (out / "state.pt").is_file():
        loaded, _ = load_checkpoint(out / "last", cfg.network)
        model.load_state_dict(loaded.state_dict())
        state = torch.load(out / "state.pt", map_location="cpu", weights_only=False)
        opt.load_state_dict(state["optimizer"])
        start_epoch, wall0, best = state["epoch"], state["wall_seconds"], state["best_val"]
        best_on = str(state.get("best_val_set", ""))
        global_step = state["step"]
    else:
        with csv_path.open("w", newline="") as fh:
            csv.DictWriter(fh, CSV_FIELDS).writeheader()
    (out / "config.json").write_text(json.dumps(cfg.to_dict(), indent=2))
    summary = data_summary(sources)
    rng = np.random.default_rng([cfg.seed, start_epoch])
    gen = torch.Generator(device="cpu").manual_seed(cfg.seed + start_epoch)
    t_start = time.perf_counter() - wall0
    final: dict[str, float] = {}
    epoch = start_epoch
    lr = cfg.lr
    for epoch in range(start_epoch + 1, cfg.epochs + 1):
        if cfg.reload_each_epoch and epoch > start_epoch + 1:
            sources = _load(cfg)
            preps = _prepare(sources, model, cfg)
            summary = data_summary(sources)
        set_train_mode(model, partial=bool(cfg.train_only))
        t0 = time.perf_counter()
        batches = epoch_batches([len(s.train) for s in sources], cfg.batch_size, rng)
        sums = dict.fromkeys(("loss", "heat", "force", "kl", "set"), 0.0)
        seen = 0
        bar = tqdm(batches, desc=f"epoch {epoch}/{cfg.epochs}", disable=not progress, leave=False)
        for step, (s, idx) in enumerate(bar):
            if cfg.max_minutes is not None and time.perf_counter() - t_start > cfg.max_minutes * 60:
                break  # time budget spent: validate and save what we have
            b = make_batch(sources[s].train, idx, hand_scale, rng if cfg.augment else None, preps[s][0],
                           max_set=cfg.max_set, mask_dropout=cfg.mask_dropout).to(device)  # fmt: skip
            terms = batch_loss(model, b, cfg, gen, device)
            frac = (epoch - 1 + step / len(batches)) / cfg.epochs
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
                sums[k] += float(terms[k].detach()) * len(idx) if k in terms else 0.0
            seen += len(idx)
            bar.set_postfix(loss=f"{float(terms['loss'].detach()):.4f}", lr=f"{lr:.2e}")
        bar.close()
        if seen == 0:
            break
        train_m = {k: v / seen for k, v in sums.items()}
        rows: list[dict[str, Any]] = [{"split": "train", **train_m, "examples": seen}]
        val_rows = _validate(model, sources, preps, cfg, device, hand_scale)
        rows += val_rows
        val_m = next((r for r in val_rows if r["split"] == "val"), None)
        secs = time.perf_counter() - t0
        with csv_path.open("a", newline="") as fh:
            w = csv.DictWriter(fh, CSV_FIELDS)
            for r in rows:
                w.writerow({"epoch": epoch, "lr": lr, "seconds": round(secs, 2), **r})
        plot_curves(csv_path, out / "curves.png")
        wall = time.perf_counter() - t_start
        final = {f"train_{k}": v for k, v in train_m.items()}
        for r in val_rows:
            skip = ("split", "examples", "open_examples")
            final.update({f"{r['split']}_{k}": float(v) for k, v in r.items() if k not in skip})
        known = set(init_card.materials) if init_card is not None else set()
        materials = sorted({m for src in sources for m in src.materials()} | known)
        card = run_card(model, cfg, summary, epoch, wall, final, device, materials, init_card)
        save_checkpoint(model, out / "last", card)
        score = float(val_m["loss"]) if val_m is not None else train_m["loss"]
        measured_on = validation_fingerprint(sources)
        if is_best(score, measured_on, best, best_on):
            best, best_on = score, measured_on
            save_checkpoint(model, out / "best", card)
        torch.save(
            {
                "optimizer": opt.state_dict(),
                "step": global_step,
                "epoch": epoch,
                "wall_seconds": wall,
                "best_val": best,
                "best_val_set": best_on,
            },
            out / "state.pt",
        )
        msg = f"epoch {epoch}: train {train_m['loss']:.4f}"
        for r in val_rows:
            msg += f"  {r['split']} {r['loss']:.4f} (heat {r['heat']:.4f}, force {r['force']:.4f}"
            msg += f", peak {r['peak']:.2f}, hit {r['hit']:.2f}, flat {r['flat']:.2f}"
            msg += f"; unmasked: hit {r['hit_open']:.2f}, flat {r['flat_open']:.2f})"
        print(msg + f"  [{secs:.0f} s]", flush=True)
        if cfg.max_minutes is not None and wall > cfg.max_minutes * 60:
            break
    return TrainResult(out, epoch, time.perf_counter() - t_start, final, best)



def _load(cfg: TrainConfig) -> list[Source]:
    """The sources of ``cfg.data``: its rigid shard directories as one source, its deformable data directories
    (``mani-lab data generate --materials cloth,rope,plasticine``; clouds resampled to the network's point count)
    as another; a run mixes them batch by batch (`research.training.sources`).

    Raises:
        ValueError: a directory holds no generated data, or no source has training examples.
    """
    from manifoundation.core.network.config import get_config

    rigid, deformable = split_dirs(list(cfg.data))
    sources = []
    if rigid:
        sources.append(load_rigid(rigid, tuple(cfg.val_splits), cfg.limit, cfg.val_limit))
    if deformable:
        n = get_config(cfg.network).num_points
        sources.append(load_deformable(deformable, tuple(cfg.val_splits), n, cfg.val_limit))
    return sources


def _prepare(sources: list[Source], model: ManiFoundationNet, cfg: TrainConfig) -> list[Prepared]:
    """Each source's precomputed point subsets and hierarchies (train, val)."""
    return [(prepare(s.train, model, cfg), prepare(s.val, model, cfg)) for s in sources]


def _validate(model: ManiFoundationNet, sources: list[Source], preps: list[Prepared], cfg: TrainConfig,
              device: torch.device, hand_scale: float) -> list[dict[str, Any]]:  # fmt: skip
    """Validation rows for metrics.csv: ``val`` over every source's validation examples (the example-weighted
    mean of each figure, the unmasked ones weighted by unmasked examples) and, with several sources,
    ``val_<kind>`` for each."""
    per: list[dict[str, Any]] = []
    for s, (_, val_prep) in zip(sources, preps, strict=True):
        if s.val is not None:
            m = evaluate(model, s.val, cfg, device, hand_scale, val_prep)
            per.append({"split": f"val_{s.kind}", **m, "examples": len(s.val)})
    if not per:
        return []
    n, n_open = sum(r["examples"] for r in per), sum(r["open_examples"] for r in per)
    total: dict[str, Any] = {"split": "val", "examples": n, "open_examples": n_open}
    for k in per[0]:
        if k not in total:  # the unmasked figures are means over the unmasked examples, the others over all
            w, den = ("open_examples", n_open) if k.endswith("_open") else ("examples", n)
            total[k] = sum(r[k] * r[w] for r in per) / max(den, 1)
    return [total, *per] if len(per) > 1 else [total]
