"""Reading generated shards for training: in-memory examples → normalised network tensors.

Every example is normalised exactly as `manifoundation.core.network.inference` normalises a request (bounding-box
centre, longest side s): positions (x − c)/s, motions and force maps / s, hand cloud / ``hand_scale_m``. Optional
augmentation rotates an example (points, normals, motion, force map) by a random rotation before normalising;
physics is rotation-invariant and the hand cloud stays in its palm frame.

Rigid and articulated examples also carry their grasp sets (`research.data.grasp_sets`, computed once per shard
and cached beside it as ``shard-*.sets.npz``): a batch holds the heatmap and force map of every valid grasp of
each example, and its CVAE target is one of them, drawn anew each time (the example's own without ``rng``).
With :class:`research.data.prepare.PreparedObjects` a batch uses the network's point subset and precomputed
hierarchy of each object.
"""

from __future__ import annotations

import json
import os
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import torch
from scipy.spatial.transform import Rotation

from manifoundation.core.network.hierarchy import PointHierarchy, gather_hierarchy
from manifoundation.core.network.model import ObjectTensors
from manifoundation.core.network.normalize import Normalizer
from manifoundation.core.network.properties import property_tensors
from research.data.grasp_sets import GraspSets, grasps_in_mask, set_maps, shard_grasp_sets
from research.data.prepare import PreparedObjects


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
SET_KEYS = ("set_contacts", "set_normals", "set_forces", "set_count")


def cached_grasp_sets(shard: Path, z: Mapping[str, np.ndarray]) -> GraspSets:
    """The shard's grasp sets, from ``shard-*.sets.npz`` beside it when that is newer, else computed from ``z``
    (the shard's arrays: its open ``np.load`` or the dict it was written from) and cached."""
    side = shard.with_name(shard.name.removesuffix(".npz") + ".sets.npz")
    if side.is_file() and side.stat().st_mtime >= shard.stat().st_mtime:
        c = np.load(side)
        return GraspSets(c["contacts"], c["normals"], c["forces"], c["count"])
    sets = shard_grasp_sets({k: z[k] for k in z})
    tmp = side.with_name(f"{side.name}.{os.getpid()}.tmp.npz")  # two readers of one shard must not share it
    np.savez(tmp, contacts=sets.contacts, normals=sets.normals, forces=sets.forces, count=sets.count)
    os.replace(tmp, side)
    return sets


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
                    sets = cached_grasp_sets(f, z)
                    for k, v in zip(SET_KEYS, (sets.contacts, sets.normals, sets.forces, sets.count), strict=True):
                        parts.setdefault(k, []).append(v[idx])
            obj_parts.setdefault("points", []).append(z["object_points"].astype(np.float32))
            obj_parts.setdefault("normals", []).append(z["object_normals"].astype(np.float32))
            for k in OBJECT_EXTRA:
                obj_parts.setdefault(k, []).append(z[f"object_{k}"])
            offset += n_obj
    if not parts:
        raise ValueError(f"no examples of splits {splits} in {dirs}")
    for k in SET_KEYS[:3]:  # shards may keep sets of different sizes (`DataConfig.max_set`): pad to the largest
        widest = max(v.shape[1] for v in parts[k])
        parts[k] = [np.pad(v, ((0, 0), (0, widest - v.shape[1]), (0, 0), (0, 0)), constant_values=np.nan)
                    for v in parts[k]]  # fmt: skip
    cat = {k: np.concatenate(v) for k, v in parts.items()}
    if limit is not None:
        cat = {k: v[:limit] for k, v in cat.items()}
    objs = {k: np.concatenate(v) for k, v in obj_parts.items()}
    extra = {k: cat[k] for k in (*EXTRA_KEYS, *SET_KEYS)}
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
        from manifoundation.core.robots import get_hand

        h = get_hand(name)
        _HAND_CLOUDS[key] = np.concatenate([h.surface_points / hand_scale_m, h.surface_normals], 1).astype(np.float32)
    return _HAND_CLOUDS[key]


@dataclass
class Batch:
    """Network tensors of a batch and its labels.

    Attributes:
        obj, hand (B, M_h, 6): the network's input; hierarchy: its precomputed sampling (None: the model's own).
        heat (B, N), force (B, N, 3): the CVAE target (one valid grasp per example), normalised units.
        set_heat (B, G, N), set_force (B, G, N, 3), set_valid (B, G): every valid grasp's maps (padding False).
    """

    obj: ObjectTensors
    hand: torch.Tensor
    heat: torch.Tensor
    force: torch.Tensor
    set_heat: torch.Tensor
    set_force: torch.Tensor
    set_valid: torch.Tensor
    hierarchy: PointHierarchy | None = None

    def to(self, device: torch.device | str) -> Batch:
        h = self.hierarchy
        if h is not None:
            h = PointHierarchy(
                [t.to(device) for t in h.xyz], [t.to(device) for t in h.groups], list(h.radii),
                [t.to(device) for t in h.up_idx], [t.to(device) for t in h.up_weights],
            )  # fmt: skip
        return Batch(
            self.obj.to(device), self.hand.to(device), self.heat.to(device), self.force.to(device),
            self.set_heat.to(device), self.set_force.to(device), self.set_valid.to(device), h,
        )  # fmt: skip


def example_sets(ex: Examples, i: int, take: np.ndarray | slice) -> tuple[np.ndarray, np.ndarray]:
    """Heatmaps (G, N) and force maps (G, N, 3) of example ``i``'s valid grasps on its object's points ``take``
    (its own labels alone when the examples carry no grasp sets, e.g. deformables)."""
    if "set_count" not in ex.extra:
        return ex.heat[i][take][None].astype(np.float64), ex.force_map[i][take][None].astype(np.float64)
    o = ex.obj_index[i]
    pts, nrm = ex.points[o][take].astype(np.float64), ex.normals[o][take].astype(np.float64)
    g = int(ex.extra["set_count"][i])
    return set_maps(pts, nrm, ex.extra["set_contacts"][i, :g], ex.extra["set_normals"][i, :g],
                    ex.extra["set_forces"][i, :g], float(ex.extra["object_scale"][o]))  # fmt: skip


def make_batch(
    ex: Examples,
    idx: np.ndarray,
    hand_scale_m: float,
    rng: np.random.Generator | None = None,
    prepared: PreparedObjects | None = None,
    max_set: int = 8,
    mask_dropout: float = 0.0,
) -> Batch:
    """Normalised tensors of examples ``idx``; ``rng`` turns on random-rotation augmentation, a random valid
    grasp as the CVAE target and, with probability ``mask_dropout``, an all-ones mask in place of a partial one
    (a partial mask is drawn around the label's contacts: a shortcut the network otherwise learns alone);
    ``prepared`` gives the network's point subsets and hierarchies. Under a partial mask only the valid grasps
    inside it (`grasps_in_mask`) are targets or count in the set loss."""
    keys = ("xyz", "normals", "motion", "mask", "heat", "force", "hand", "s", "set_heat", "set_force", "valid")
    rows: dict[str, list[Any]] = {k: [] for k in keys}
    for i in idx:
        o = ex.obj_index[i]
        take = prepared.subsets[o] if prepared is not None else slice(None)
        pts, nrm = ex.points[o].astype(np.float64), ex.normals[o].astype(np.float64)
        set_heat, set_force = example_sets(ex, i, take)
        mot = ex.motion[i].astype(np.float64)
        rot = np.eye(3)
        if rng is not None:
            rot = Rotation.random(random_state=int(rng.integers(2**31))).as_matrix()
        pts, nrm, mot = pts @ rot.T, nrm @ rot.T, mot @ rot.T
        nz = Normalizer.fit(pts)  # on the whole cloud, as inference normalises a request
        g_n = min(len(set_heat), max_set)
        heat_pad = np.zeros((max_set, len(set_heat[0])))
        force_pad = np.zeros((max_set, len(set_heat[0]), 3))
        heat_pad[:g_n], force_pad[:g_n] = set_heat[:g_n], nz.vectors(set_force[:g_n] @ rot.T)
        drop = rng is not None and mask_dropout > 0.0 and rng.random() < mask_dropout
        mask = np.ones(len(pts), dtype=bool) if drop else np.asarray(ex.mask[i], dtype=bool)
        usable = np.arange(max_set) < g_n
        if not mask.all() and "set_contacts" in ex.extra:
            usable[:g_n] &= grasps_in_mask(ex.points[o], mask, ex.extra["set_contacts"][i][:g_n], g_n)
        pick = int(rng.choice(np.flatnonzero(usable))) if rng is not None else 0
        rows["xyz"].append(nz.points(pts[take]))
        rows["normals"].append(nrm[take])
        rows["motion"].append(nz.vectors(mot[take]))
        rows["mask"].append(mask[take].astype(np.float64))
        rows["heat"].append(heat_pad[pick])
        rows["force"].append(force_pad[pick])
        rows["set_heat"].append(heat_pad)
        rows["set_force"].append(force_pad)
        rows["valid"].append(usable)
        rows["hand"].append(hand_cloud(str(ex.hand[i]), hand_scale_m))
        rows["s"].append(nz.scale)
    if "properties" in ex.extra:  # every property channel the examples carry (deformables), NaN = absent
        from manifoundation.core.network.properties import PROPERTY_NAMES

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
    hierarchy = None
    if prepared is not None:
        hierarchy = gather_hierarchy(obj.xyz, [prepared.index[o] for o in ex.obj_index[idx]], prepared.levels)
    valid = torch.as_tensor(np.stack(rows["valid"]))
    return Batch(obj, t("hand"), t("heat"), t("force"), t("set_heat"), t("set_force"), valid, hierarchy)
