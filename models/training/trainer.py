"""The training loop of `mani train`: AdamW, warm-up + cosine schedule, Eq. (3), per-epoch validation,
CSV + PNG curves, a checkpoint every epoch, resume.

Run directory layout (``cfg.out``)::

    config.json            the resolved TrainConfig
    metrics.csv            epoch, split, loss terms, validation figures (peak, hit, flat), lr, seconds
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
from models.network import ModelCard, create_model, load_checkpoint, save_checkpoint
from models.training.config import TrainConfig
from models.training.objective import batch_loss, prepare
from models.training.validation import evaluate, plot_curves

CSV_FIELDS = (
    "epoch", "split", "loss", "heat", "force", "kl", "set", "peak", "hit", "flat", "hit_open", "flat_open", "lr",
    "seconds", "examples",
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


def data_summary(train: Examples, val: Examples | None) -> dict[str, Any]:
    """Counts for the model card."""

    def counts(ex: Examples) -> dict[str, Any]:
        hands, n = np.unique(ex.hand, return_counts=True)
        out: dict[str, Any] = {
            "examples": len(ex),
            "objects": len(np.unique(ex.obj_index)),
            "hands": {str(h): int(c) for h, c in zip(hands, n, strict=True)},
        }
        if "articulated" in ex.extra:
            out["articulated"] = int(np.asarray(ex.extra["articulated"]).sum())
        if "material" in ex.extra:
            kinds, m = np.unique(ex.extra["material"], return_counts=True)
            out["materials"] = {str(k): int(c) for k, c in zip(kinds, m, strict=True)}
        return out

    out = {"train": counts(train)}
    if val is not None:
        out["val"] = counts(val)
    return out


def train(cfg: TrainConfig, resume: bool = False, progress: bool = True) -> TrainResult:
    """Train (or resume) a network as configured; see the module docstring for the outputs."""
    from tqdm import tqdm

    torch.set_num_threads(cfg.threads)
    device = pick_device(cfg.device)
    out = Path(cfg.out)
    out.mkdir(parents=True, exist_ok=True)
    train_ex, val_ex = _load(cfg)
    model = create_model(cfg.network, seed=cfg.seed).to(device)
    if cfg.init_from is not None and not resume:
        model.load_state_dict(load_checkpoint(cfg.init_from, cfg.network)[0].state_dict())
    train_prep, val_prep = prepare(train_ex, model, cfg), prepare(val_ex, model, cfg)
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
            train_prep, val_prep = prepare(train_ex, model, cfg), prepare(val_ex, model, cfg)
            summary = data_summary(train_ex, val_ex)
        # drop the last partial batch: BatchNorm cannot train on one example, and a tiny batch is a noisy step
        steps_per_epoch = max(1, len(train_ex) // cfg.batch_size)
        model.train()
        t0 = time.perf_counter()
        perm = rng.permutation(len(train_ex))
        sums = dict.fromkeys(("loss", "heat", "force", "kl", "set"), 0.0)
        seen = 0
        bar = tqdm(range(steps_per_epoch), desc=f"epoch {epoch}/{cfg.epochs}", disable=not progress, leave=False)
        for step in bar:
            if cfg.max_minutes is not None and time.perf_counter() - t_start > cfg.max_minutes * 60:
                break  # time budget spent: validate and save what we have
            idx = perm[step * cfg.batch_size : (step + 1) * cfg.batch_size]
            b = make_batch(train_ex, idx, hand_scale, rng if cfg.augment else None, train_prep,
                           max_set=cfg.max_set, mask_dropout=cfg.mask_dropout).to(device)  # fmt: skip
            terms = batch_loss(model, b, cfg, gen, device)
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
                sums[k] += float(terms[k].detach()) * len(idx) if k in terms else 0.0
            seen += len(idx)
            bar.set_postfix(loss=f"{float(terms['loss'].detach()):.4f}", lr=f"{lr:.2e}")
        bar.close()
        if seen == 0:
            break
        train_m = {k: v / seen for k, v in sums.items()}
        rows = [{"split": "train", **train_m, "examples": seen}]
        val_m = evaluate(model, val_ex, cfg, device, hand_scale, val_prep) if val_ex is not None else None
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
        card = _card(model, cfg, summary, epoch, wall, final, device, _materials(train_ex))
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
            msg += f", peak {val_m['peak']:.2f}, hit {val_m['hit']:.2f}, flat {val_m['flat']:.2f}"
            msg += f"; unmasked: hit {val_m['hit_open']:.2f}, flat {val_m['flat_open']:.2f})"
        print(msg + f"  [{secs:.0f} s]", flush=True)
        if cfg.max_minutes is not None and wall > cfg.max_minutes * 60:
            break
    return TrainResult(out, epoch, time.perf_counter() - t_start, final, best)


def _load(cfg: TrainConfig) -> tuple[Examples, Examples | None]:
    """The training and validation examples of ``cfg.data``: rigid shard directories, or one deformable data
    directory (``mani data generate --materials cloth,rope,plasticine``; its clouds resampled to the network's
    point count). Mixing the two kinds is refused: their label sets differ (grasp sets vs single labels)."""
    deformable = [d for d in cfg.data if _is_deformable(d)]
    if deformable:
        if len(deformable) != len(cfg.data) or len(deformable) > 1:
            raise ValueError("data: one deformable data directory, alone (rigid and deformable examples are not "
                             f"mixed in one run yet): {list(cfg.data)}")
        from models.data.deformable_dataset import load_deformable_examples
        from models.network.config import get_config

        n = get_config(cfg.network).num_points
        train_ex = load_deformable_examples(deformable[0], ("train",), num_points=n)
        try:
            val_ex: Examples | None = load_deformable_examples(deformable[0], tuple(cfg.val_splits), num_points=n)
        except ValueError:
            val_ex = None
        return train_ex, _first(val_ex, cfg.val_limit)
    train_ex = load_examples(list(cfg.data), ("train",), limit=cfg.limit)
    try:
        val_ex = load_examples(list(cfg.data), tuple(cfg.val_splits), limit=cfg.val_limit)
    except ValueError:
        val_ex = None
    return train_ex, val_ex


def _materials(ex: Examples) -> list[str] | None:
    """The deformable materials ``ex`` holds (None: rigid shards, which carry no material)."""
    if "material" not in ex.extra:
        return None
    return sorted({str(m) for m in ex.extra["material"]})


def _is_deformable(data_dir: str) -> bool:
    from models.data.deformable_generate import MANIFEST, SUBDIR

    return (Path(data_dir) / SUBDIR / MANIFEST).is_file() and not (Path(data_dir) / "manifest.json").is_file()


def _first(ex: Examples | None, limit: int | None) -> Examples | None:
    """The first ``limit`` examples of ``ex`` (validation sets are capped like the rigid loader caps them)."""
    if ex is None or limit is None or len(ex) <= limit:
        return ex
    from dataclasses import replace

    keep = slice(0, limit)
    return replace(ex, obj_index=ex.obj_index[keep], hand=ex.hand[keep], split=ex.split[keep],
                   friction=ex.friction[keep], motion=ex.motion[keep], heat=ex.heat[keep],
                   force_map=ex.force_map[keep], mask=ex.mask[keep],
                   extra={k: v[keep] for k, v in ex.extra.items()})  # fmt: skip


def _card(
    model: torch.nn.Module,
    cfg: TrainConfig,
    summary: dict[str, Any],
    epoch: int,
    wall: float,
    metrics: dict[str, float],
    device: torch.device,
    materials: list[str] | None = None,
) -> ModelCard:
    materials = materials or ["rigid", "articulated"]
    note = ("Trained on rigid and articulated (revolute/prismatic) examples only; requests for deformable "
            "materials are out of its training distribution.") if "rigid" in materials else (
            f"Trained on deformable examples only ({', '.join(materials)}); rigid requests are out of its "
            "training distribution.")  # fmt: skip
    return ModelCard.for_model(
        model,  # type: ignore[arg-type]
        trained=True,
        training_data={
            **summary,
            "generator": "models.data (hierarchical grasp sampling, see models/data/__init__.py; labels: each "
            "example's grasp set, models/data/grasp_sets.py)",
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
        materials=materials,
        notes=note,
    )
