"""Test cases from generated shards: the object (mesh regenerated from the manifest's seed), the motion,
mask, friction and (articulated) joint of each ``test_so`` / ``test_uo`` example, with its valid contact region:
the points where the heatmap of any grasp that can produce the motion is ≥ 0.5 (`research.data.grasp_sets`)."""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from research.data.dataset import cached_grasp_sets
from research.data.generate import DataConfig, make_dataset_object
from research.data.grasp_sets import GraspSets, set_region


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
    delta_x: np.ndarray | None = None  # (3,) rigid: the motion's translation (m) and rotation vector (rad)
    delta_theta: np.ndarray | None = None
    valid_region: np.ndarray | None = None  # (N,) bool: in the contact region of a grasp that can do the task
    grasp_contacts: np.ndarray | None = None  # (G, C, 3) the valid grasps (own first), NaN rows padding
    grasp_normals: np.ndarray | None = None  # (G, C, 3)
    grasp_forces: np.ndarray | None = None  # (G, C, 3) forces that produce the motion
    object_index: int = -1  # the object's index in its data set (`research.data.generate.make_dataset_object`)


def data_config(data_dir: str | Path) -> DataConfig:
    """The `DataConfig` a generated data directory was made with (its manifest's)."""
    return _manifest_config(json.loads((Path(data_dir) / "manifest.json").read_text()))


def _manifest_config(manifest: dict[str, Any]) -> DataConfig:
    fields: dict[str, Any] = {k: tuple(v) if isinstance(v, list) else v for k, v in manifest["config"].items()}
    return DataConfig(**fields)


def load_cases(
    data_dir: str | Path,
    split: str,
    limit: int,
    seed: int = 0,
    articulated: bool | None = None,
    label_hand: str | None = None,
) -> list[TestCase]:
    """Up to ``limit`` cases of ``split`` (labelled with ``label_hand``'s grasps, when given), one per object
    first (then more per object), seeded order."""
    d = Path(data_dir)
    manifest = json.loads((d / "manifest.json").read_text())
    cfg = _manifest_config(manifest)
    rows: list[tuple[int, int, int, str]] = []  # (shard, example, global object, object id)
    for s in manifest["shards"].values():
        z = np.load(d / s["file"], allow_pickle=False)
        if int(z["num_examples"]) == 0:
            continue
        for e in np.flatnonzero(z["split"] == split).tolist():
            if articulated is not None and bool(z["articulated"][e]) != articulated:
                continue
            if label_hand is not None and str(z["hand"][e]) != label_hand:
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
        path = d / f"shard-{shard:05d}.npz"
        z = np.load(path, allow_pickle=False)
        if gi not in cache:
            cache[gi] = make_dataset_object(cfg, gi)
        obj = cache[gi]
        if obj.id != oid:
            raise ValueError(f"object {gi} regenerated as {obj.id}, shard says {oid}: code changed since generation")
        cases.append(
            TestCase(
                split=split,
                object_id=oid,
                object_index=gi,
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
                delta_x=z["delta_x"][e].astype(np.float64),
                delta_theta=z["delta_theta"][e].astype(np.float64),
                **_grasp_set(cached_grasp_sets(path, z), e, obj.points, obj.normals),
            )
        )
    return cases


def _grasp_set(sets: GraspSets, e: int, points: np.ndarray, normals: np.ndarray) -> dict[str, np.ndarray]:
    """Example ``e``'s valid grasps (``grasp_contacts``, ``grasp_normals``, ``grasp_forces`` (G, C, 3)) and its
    ``valid_region`` (N,): the points where any of them has heat ≥ ``REGION_HEAT`` (0.5)."""
    g = int(sets.count[e])
    contacts, grasp_normals, forces = sets.contacts[e, :g], sets.normals[e, :g], sets.forces[e, :g]
    return {"grasp_contacts": contacts, "grasp_normals": grasp_normals, "grasp_forces": forces,
            "valid_region": set_region(points, normals, contacts, grasp_normals, forces)}  # fmt: skip


def motion_kind(case: TestCase) -> str:
    """``lift``, ``press``, ``push`` (translation-led: up, down, sideways) or ``rotation`` (the rotation moves the
    farthest point more than the translation does); ``joint`` for articulated cases."""
    if case.articulated or case.delta_x is None or case.delta_theta is None:
        return "joint"
    reach = float(np.linalg.norm(case.points - case.points.mean(axis=0), axis=1).max())
    shift = float(np.linalg.norm(case.delta_x))
    if float(np.linalg.norm(case.delta_theta)) * reach > shift:
        return "rotation"
    up = float(case.delta_x[2]) / max(shift, 1e-12)
    return "lift" if up > 0.7 else "press" if up < -0.7 else "push"
