"""Where a training run's examples come from: rigid shard directories and deformable data directories, as
*sources* that one run mixes.

A rigid source carries each example's grasp set (up to ``max_set`` valid grasps); a deformable source one label
an example, on clouds resampled to the network's point count. A batch is drawn from one source only, so its
arrays keep one shape; an epoch visits every source's examples once, its batches in a shuffled order, so each
material is seen in proportion to its examples. One source behaves exactly as the single-source loop did (the
same permutation, the same batches).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from research.data.dataset import Examples, load_examples

RIGID = "rigid"
DEFORMABLE = "deformable"
RIGID_MATERIALS = ("rigid", "articulated")


@dataclass
class Source:
    """The examples of one kind of data: ``train`` and (optional) ``val``."""

    kind: str  # RIGID or DEFORMABLE
    dirs: tuple[str, ...]
    train: Examples
    val: Examples | None

    def materials(self) -> list[str]:
        """The materials this source teaches (rigid shards hold rigid and articulated objects)."""
        if self.kind == RIGID:
            return list(RIGID_MATERIALS)
        return sorted({str(m) for m in self.train.extra["material"]})


def split_dirs(data: list[str]) -> tuple[list[str], list[str]]:
    """``data`` split into rigid shard directories and deformable data directories (a directory generated with
    both rigid objects and deformable materials is in both).

    Raises:
        ValueError: a directory holds neither kind of data.
    """
    from research.data.deformable_generate import MANIFEST, SUBDIR

    rigid, deformable = [], []
    for d in data:
        has_rigid, has_deformable = (Path(d) / "manifest.json").is_file(), (Path(d) / SUBDIR / MANIFEST).is_file()
        if not has_rigid and not has_deformable:
            raise ValueError(f"data: {d} holds no generated data (no manifest.json, no {SUBDIR}/{MANIFEST})")
        if has_rigid:
            rigid.append(d)
        if has_deformable:
            deformable.append(d)
    return rigid, deformable


def load_rigid(dirs: list[str], val_splits: tuple[str, ...], limit: int | None, val_limit: int | None) -> Source:
    """The rigid and articulated examples of ``dirs`` (their grasp sets included)."""
    train = load_examples(list(dirs), ("train",), limit=limit)
    try:
        val: Examples | None = load_examples(list(dirs), val_splits, limit=val_limit)
    except ValueError:
        val = None
    return Source(RIGID, tuple(dirs), train, val)


def load_deformable(dirs: list[str], val_splits: tuple[str, ...], num_points: int, val_limit: int | None) -> Source:
    """The deformable examples of ``dirs``, clouds resampled to ``num_points``."""
    from research.data.deformable_dataset import load_deformable_examples

    def read(splits: tuple[str, ...]) -> list[Examples]:
        parts = []
        for d in dirs:  # a directory still being generated may not hold every split yet
            try:
                parts.append(load_deformable_examples(d, splits, num_points=num_points))
            except ValueError:
                continue
        return parts

    train, vals = read(("train",)), read(val_splits)
    if not train:
        raise ValueError(f"no deformable training examples in {list(dirs)}")
    val = first_examples(concat_examples(vals), val_limit) if vals else None
    return Source(DEFORMABLE, tuple(dirs), concat_examples(train), val)


def concat_examples(parts: list[Examples]) -> Examples:
    """One ``Examples`` of ``parts`` (same point count and extra keys; object indices offset)."""
    if len(parts) == 1:
        return parts[0]
    offsets = np.cumsum([0] + [len(p.points) for p in parts[:-1]])
    keys = set(parts[0].extra)
    if any(set(p.extra) != keys for p in parts):
        raise ValueError("examples to concatenate carry different extra arrays")

    def cat(name: str) -> np.ndarray:
        return np.concatenate([getattr(p, name) for p in parts])

    return Examples(cat("points"), cat("normals"),
                    np.concatenate([p.obj_index + o for p, o in zip(parts, offsets, strict=True)]), cat("hand"),
                    cat("split"), cat("friction"), cat("motion"), cat("heat"), cat("force_map"), cat("mask"),
                    {k: np.concatenate([p.extra[k] for p in parts]) for k in keys})  # fmt: skip


def first_examples(ex: Examples | None, limit: int | None) -> Examples | None:
    """The first ``limit`` examples of ``ex`` (validation sets are capped like the rigid loader caps them)."""
    if ex is None or limit is None or len(ex) <= limit:
        return ex
    keep = slice(0, limit)
    return replace(ex, obj_index=ex.obj_index[keep], hand=ex.hand[keep], split=ex.split[keep],
                   friction=ex.friction[keep], motion=ex.motion[keep], heat=ex.heat[keep],
                   force_map=ex.force_map[keep], mask=ex.mask[keep],
                   extra={k: v[keep] for k, v in ex.extra.items()})  # fmt: skip


def epoch_batches(sizes: list[int], batch_size: int, rng: np.random.Generator) -> list[tuple[int, np.ndarray]]:
    """One epoch's batches as (source index, example indices), every source's examples once, the last partial
    batch of each dropped (BatchNorm cannot train on one example).

    With one source this is the single-source loop's order (one permutation, consecutive slices); with several
    the batches are shuffled across sources.
    """
    batches: list[tuple[int, np.ndarray]] = []
    for s, n in enumerate(sizes):
        perm = rng.permutation(n)
        steps = max(1, n // batch_size) if len(sizes) == 1 else n // batch_size
        batches += [(s, perm[k * batch_size : (k + 1) * batch_size]) for k in range(steps)]
    if len(sizes) > 1:
        batches = [batches[i] for i in rng.permutation(len(batches))]
    return batches


def data_summary(sources: list[Source]) -> dict[str, Any]:
    """Counts for the model card: ``train`` and ``val`` over all sources (each by hand, material), and with
    several sources the same per source under ``sources``."""

    def counts(parts: list[Examples]) -> dict[str, Any]:
        hands: dict[str, int] = {}
        kinds: dict[str, int] = {}
        out: dict[str, Any] = {"examples": sum(len(ex) for ex in parts),
                               "objects": sum(len(np.unique(ex.obj_index)) for ex in parts)}  # fmt: skip
        for ex in parts:
            for h, c in zip(*np.unique(ex.hand, return_counts=True), strict=True):
                hands[str(h)] = hands.get(str(h), 0) + int(c)
            if "articulated" in ex.extra:
                out["articulated"] = out.get("articulated", 0) + int(np.asarray(ex.extra["articulated"]).sum())
            if "material" in ex.extra:
                for k, c in zip(*np.unique(ex.extra["material"], return_counts=True), strict=True):
                    kinds[str(k)] = kinds.get(str(k), 0) + int(c)
        out["hands"] = hands
        if kinds:
            out["materials"] = kinds
        return out

    vals = [s.val for s in sources if s.val is not None]
    out: dict[str, Any] = {"train": counts([s.train for s in sources])}
    if vals:
        out["val"] = counts(vals)
    if len(sources) > 1:
        out["sources"] = {s.kind: {"dirs": list(s.dirs), "train": counts([s.train])} for s in sources}
    return out
