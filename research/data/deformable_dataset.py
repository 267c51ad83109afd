"""Deformable examples as training `research.data.dataset.Examples`, so the one trainer reads every material.

Each body's cloud is resampled to ``num_points`` exactly as the network resamples a request
(`manifoundation.core.network.resample`: farthest-point sampling down, even repetition up), and every per-point array of
its examples (target motion, heatmap, motion map as the force map, mask) is read at the same indices. Properties go
in ``extra["properties"]`` (E, 6) in the network's channel order, NaN where a material has none (the trainer's
batches then condition on all of them, not only friction); the hand is ``hand`` for every example (the network
takes one; a deformable's answer does not depend on it beyond H).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from manifoundation.core.pipeline.deformable import DEFORMABLE_HAND
from research.data.dataset import Examples
from research.data.deformable_generate import MANIFEST, PROPERTY_KEYS, SUBDIR, load_body_file

DEFAULT_POINTS = 256
DEFAULT_HAND = DEFORMABLE_HAND  # the served pipeline answers a robot-less request with this hand


def body_files(data_dir: str | Path) -> list[Path]:
    """The body files a data directory's deformable manifest records (sorted)."""
    d = Path(data_dir) / SUBDIR
    manifest = json.loads((d / MANIFEST).read_text())
    return sorted(d / b["file"] for b in manifest["bodies"].values() if (d / b["file"]).is_file())


def load_deformable_examples(data_dir: str | Path, splits: tuple[str, ...] = ("train",),
                             num_points: int = DEFAULT_POINTS, hand: str = DEFAULT_HAND,
                             materials: tuple[str, ...] | None = None) -> Examples:  # fmt: skip
    """The deformable examples of ``splits`` under ``data_dir`` (see the module doc).

    Raises:
        ValueError: no example matches.
    """
    from manifoundation.core.network.properties import PROPERTY_NAMES
    from manifoundation.core.network.resample import resample

    channel = [PROPERTY_KEYS.index(name) for name in PROPERTY_NAMES]
    objs: dict[str, list[np.ndarray]] = {"points": [], "normals": []}
    rows: dict[str, list[np.ndarray]] = {}
    for path in body_files(data_dir):
        z = load_body_file(path)
        if materials is not None and str(z["material"]) not in materials:
            continue
        n_ex = int(z["num_examples"])
        sel = np.flatnonzero(np.isin(z["split"], splits)) if n_ex else np.zeros(0, dtype=np.int64)
        if sel.size == 0:
            continue
        take = resample(z["points"], num_points).indices
        obj = len(objs["points"])
        objs["points"].append(z["points"][take].astype(np.float32))
        objs["normals"].append(z["normals"][take].astype(np.float32))
        props = np.asarray(z["properties"], dtype=np.float64)[channel]
        for key, value in (("motion", z["motion"][sel][:, take]), ("heat", z["heat"][sel][:, take]),
                           ("force_map", z["motion_map"][sel][:, take]), ("mask", z["mask"][sel][:, take]),
                           ("split", z["split"][sel]), ("obj_index", np.full(sel.size, obj)),
                           ("friction", np.full(sel.size, props[0])), ("properties", np.tile(props, (sel.size, 1))),
                           ("material", np.full(sel.size, str(z["material"]))),
                           ("procedure", z["procedure"][sel])):  # fmt: skip
            rows.setdefault(key, []).append(np.asarray(value))
    if not rows:
        raise ValueError(f"no deformable examples of splits {splits} under {data_dir}")
    cat = {k: np.concatenate(v) for k, v in rows.items()}
    extra = {k: cat[k] for k in ("properties", "material", "procedure")}
    return Examples(np.stack(objs["points"]), np.stack(objs["normals"]), cat["obj_index"],
                    np.full(len(cat["split"]), hand), cat["split"], cat["friction"], cat["motion"].astype(np.float32),
                    cat["heat"].astype(np.float32), cat["force_map"].astype(np.float32), cat["mask"].astype(bool),
                    extra)  # fmt: skip
