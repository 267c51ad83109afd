"""Test cases from generated shards: the object (mesh regenerated from the manifest's seed), the motion,
mask, friction and (articulated) joint of each ``test_so`` / ``test_uo`` example."""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from models.data.generate import DataConfig, make_dataset_object


@dataclass
class TestCase:
    """One held-out example in request form."""

    split: str
    object_id: str
    label_hand: str  # the hand whose grasp produced the label
    points: np.ndarray
    normals: np.ndarray
    mesh_vertices: np.ndarray
    mesh_faces: np.ndarray
    motion: np.ndarray
    mask: np.ndarray
    friction: float
    articulated: bool
    joint_type: str
    joint_axis: np.ndarray
    joint_origin: np.ndarray
    joint_amount: float


def load_cases(
    data_dir: str | Path, split: str, limit: int, seed: int = 0, articulated: bool | None = None
) -> list[TestCase]:
    """Up to ``limit`` cases of ``split``, one per object first (then more per object), seeded order."""
    d = Path(data_dir)
    manifest = json.loads((d / "manifest.json").read_text())
    cfg_d: dict[str, Any] = {k: tuple(v) if isinstance(v, list) else v for k, v in manifest["config"].items()}
    cfg = DataConfig(**cfg_d)
    rows: list[tuple[int, int, int, str]] = []  # (shard, example, global object, object id)
    for s in manifest["shards"].values():
        z = np.load(d / s["file"], allow_pickle=False)
        if int(z["num_examples"]) == 0:
            continue
        for e in np.flatnonzero(z["split"] == split).tolist():
            if articulated is not None and bool(z["articulated"][e]) != articulated:
                continue
            oi = int(z["obj_index"][e])
            rows.append((s["index"], int(e), s["index"] * cfg.objects_per_shard + oi, str(z["object_ids"][oi])))
    rng = np.random.default_rng(seed)
    rng.shuffle(rows)
    seen: set[str] = set()
    first = [r for r in rows if not (r[3] in seen or seen.add(r[3]))]  # type: ignore[func-returns-value]
    rest = [r for r in rows if r not in first]
    chosen = (first + rest)[:limit]
    cases = []
    cache: dict[int, Any] = {}
    for shard, e, gi, oid in chosen:
        z = np.load(d / f"shard-{shard:05d}.npz", allow_pickle=False)
        if gi not in cache:
            cache[gi] = make_dataset_object(cfg, gi)
        obj = cache[gi]
        if obj.id != oid:
            raise ValueError(f"object {gi} regenerated as {obj.id}, shard says {oid}: code changed since generation")
        cases.append(
            TestCase(
                split=split,
                object_id=oid,
                label_hand=str(z["hand"][e]),
                points=obj.points,
                normals=obj.normals,
                mesh_vertices=np.asarray(obj.mesh.vertices),
                mesh_faces=np.asarray(obj.mesh.faces),
                motion=z["motion"][e].astype(np.float64),
                mask=z["mask"][e].astype(bool),
                friction=float(z["friction"][e]),
                articulated=bool(z["articulated"][e]),
                joint_type=str(z["joint_type"][e]),
                joint_axis=z["joint_axis"][e],
                joint_origin=z["joint_origin"][e],
                joint_amount=float(z["joint_amount"][e]),
            )
        )
    return cases
