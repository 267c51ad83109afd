"""Reading generated shards for training: in-memory examples → normalised network tensors.

Every example is normalised exactly as `models.network.inference` normalises a request (bounding-box centre,
longest side s): positions (x − c)/s, motions and force maps / s, hand cloud / ``hand_scale_m``. Optional
augmentation rotates an example (points, normals, motion, force map) by a random rotation before normalising;
physics is rotation-invariant and the hand cloud stays in its palm frame.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import torch
from scipy.spatial.transform import Rotation

from models.network.model import ObjectTensors
from models.network.normalize import Normalizer
from models.network.properties import property_tensors


@dataclass
class Examples:
    """Examples of one or more splits (arrays stacked over examples; objects shared by index)."""

    points: np.ndarray  # (O, N, 3) per object
    normals: np.ndarray  # (O, N, 3)
    obj_index: np.ndarray  # (E,)
    hand: np.ndarray  # (E,) str
    split: np.ndarray  # (E,) str
    friction: np.ndarray  # (E,)
    motion: np.ndarray  # (E, N, 3)
    heat: np.ndarray  # (E, N)
    force_map: np.ndarray  # (E, N, 3)
    mask: np.ndarray  # (E, N) bool
    extra: dict[str, np.ndarray]  # contacts, forces, palm poses, joints, object ids, ...

    def __len__(self) -> int:
        return len(self.hand)


def shard_files(data_dir: str | Path) -> list[Path]:
    """Shard files recorded in the manifest (sorted by index)."""
    d = Path(data_dir)
    manifest = json.loads((d / "manifest.json").read_text())
    shards = sorted(manifest["shards"].values(), key=lambda s: s["index"])
    return [d / s["file"] for s in shards if (d / s["file"]).is_file()]


EXTRA_KEYS = (
    "contacts",
    "contact_normals",
    "forces",
    "num_contacts",
    "palm_pos",
    "palm_quat",
    "q",
    "articulated",
    "joint_type",
    "joint_axis",
    "joint_origin",
    "joint_amount",
    "delta_x",
    "delta_theta",
)
OBJECT_EXTRA = ("ids", "kinds", "scale", "centre", "mass", "inertia", "length", "split")


def load_examples(
    data_dir: str | Path | list[str | Path],
    splits: tuple[str, ...] = ("train",),
    hands: tuple[str, ...] | None = None,
    limit: int | None = None,
) -> Examples:
    """Load the examples of ``splits`` (and ``hands``, when given) from one or more data directories."""
    dirs = data_dir if isinstance(data_dir, list) else [data_dir]
    parts: dict[str, list[np.ndarray]] = {}
    obj_parts: dict[str, list[np.ndarray]] = {}
    offset = 0
    for d in dirs:
        for f in shard_files(d):
            z = np.load(f, allow_pickle=False)
            n_obj = len(z["object_ids"])
            if int(z["num_examples"]) > 0:
                sel = np.isin(z["split"], splits)
                if hands is not None:
                    sel &= np.isin(z["hand"], hands)
                idx = np.flatnonzero(sel)
                if idx.size:
                    for k in ("hand", "split", "friction", "motion", "heat", "force_map", "mask", *EXTRA_KEYS):
                        parts.setdefault(k, []).append(z[k][idx])
                    parts.setdefault("obj_index", []).append(z["obj_index"][idx] + offset)
            obj_parts.setdefault("points", []).append(z["object_points"].astype(np.float32))
            obj_parts.setdefault("normals", []).append(z["object_normals"].astype(np.float32))
            for k in OBJECT_EXTRA:
                obj_parts.setdefault(k, []).append(z[f"object_{k}"])
            offset += n_obj
    if not parts:
        raise ValueError(f"no examples of splits {splits} in {dirs}")
    cat = {k: np.concatenate(v) for k, v in parts.items()}
    if limit is not None:
        cat = {k: v[:limit] for k, v in cat.items()}
    objs = {k: np.concatenate(v) for k, v in obj_parts.items()}
    extra = {k: cat[k] for k in EXTRA_KEYS}
    for k in OBJECT_EXTRA:
        extra[f"object_{k}"] = objs[k]
    return Examples(
        objs["points"],
        objs["normals"],
        cat["obj_index"],
        cat["hand"],
        cat["split"],
        cat["friction"],
        cat["motion"],
        cat["heat"],
        cat["force_map"],
        cat["mask"],
        extra,
    )


_HAND_CLOUDS: dict[str, np.ndarray] = {}


def hand_cloud(name: str, hand_scale_m: float) -> np.ndarray:
    """(1024, 6) network hand input (points / hand_scale_m, normals) of a built-in hand (cached)."""
    key = f"{name}:{hand_scale_m}"
    if key not in _HAND_CLOUDS:
        from models.robots import get_hand

        h = get_hand(name)
        _HAND_CLOUDS[key] = np.concatenate([h.surface_points / hand_scale_m, h.surface_normals], 1).astype(np.float32)
    return _HAND_CLOUDS[key]


@dataclass
class Batch:
    obj: ObjectTensors
    hand: torch.Tensor  # (B, M_h, 6)
    heat: torch.Tensor  # (B, N)
    force: torch.Tensor  # (B, N, 3) normalised units

    def to(self, device: torch.device | str) -> Batch:
        return Batch(self.obj.to(device), self.hand.to(device), self.heat.to(device), self.force.to(device))


def make_batch(ex: Examples, idx: np.ndarray, hand_scale_m: float, rng: np.random.Generator | None = None) -> Batch:
    """Normalised tensors of examples ``idx``; ``rng`` turns on random-rotation augmentation."""
    rows: dict[str, list[Any]] = {k: [] for k in ("xyz", "normals", "motion", "mask", "heat", "force", "hand", "s")}
    for i in idx:
        o = ex.obj_index[i]
        pts, nrm = ex.points[o].astype(np.float64), ex.normals[o].astype(np.float64)
        mot, frc = ex.motion[i].astype(np.float64), ex.force_map[i].astype(np.float64)
        if rng is not None:
            rot = Rotation.random(random_state=int(rng.integers(2**31))).as_matrix()
            pts, nrm, mot, frc = pts @ rot.T, nrm @ rot.T, mot @ rot.T, frc @ rot.T
        nz = Normalizer.fit(pts)
        rows["xyz"].append(nz.points(pts))
        rows["normals"].append(nrm)
        rows["motion"].append(nz.vectors(mot))
        rows["force"].append(nz.vectors(frc))
        rows["mask"].append(ex.mask[i].astype(np.float64))
        rows["heat"].append(ex.heat[i])
        rows["hand"].append(hand_cloud(str(ex.hand[i]), hand_scale_m))
        rows["s"].append(nz.scale)
    if "properties" in ex.extra:  # every property channel the examples carry (deformables), NaN = absent
        from models.network.properties import PROPERTY_NAMES

        table = ex.extra["properties"]
        props = [{n: float(v) for n, v in zip(PROPERTY_NAMES, table[i], strict=True) if np.isfinite(v)} for i in idx]
    else:
        props = [{"friction": float(ex.friction[i])} for i in idx]
    values, present = property_tensors(props)

    def t(key: str) -> torch.Tensor:
        return torch.as_tensor(np.stack(rows[key]), dtype=torch.float32)

    obj = ObjectTensors(
        xyz=t("xyz"),
        normals=t("normals"),
        motion=t("motion"),
        mask=t("mask"),
        prop_values=values,
        prop_mask=present,
        scale=torch.tensor(rows["s"], dtype=torch.float32),
    )
    return Batch(obj, t("hand"), t("heat"), t("force"))
