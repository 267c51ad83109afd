"""Sharded, seeded, resumable data generation with worker processes.

Object ``i`` of a data set (seed S) is ``make_object(kind_i, size_i, seed_i)`` with everything drawn from
``default_rng([S, i])``; its split is fixed by its id (``test`` when sha1(id) mod 1000 < 1000·test_fraction).
A (object, hand) job draws from ``default_rng([S, i, hand index])``, so a shard's content depends only on the
seed and the configuration, not on scheduling. Shard k holds objects [k·B, (k+1)·B); a finished shard is
written atomically and recorded in ``manifest.json``; a rerun skips recorded shards (resume).

Splits of examples: ``train`` (train objects, seen motions), ``test_so`` (train objects, unseen motions:
Seen-Object/Unseen-Motion), ``test_uo`` (test objects, unseen motions: Unseen-Object/Unseen-Motion). Held-out
hands produce test examples only. ``test_objects_only`` labels the test objects alone: every object is still
recorded, so shard k and the object indices are those of the full data set and its ``test_uo`` examples are the
same — the evaluation set without the ~85 % of the work that only training needs.
"""

from __future__ import annotations

import hashlib
import json
import os
import time
from collections import Counter
from collections.abc import Callable, Iterator
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from research.data.runs import run_jobs, write_manifest

if TYPE_CHECKING:
    from manifoundation.core.objects import ProceduralObject

TRAIN_HANDS = ("allegro", "leap", "panda_gripper", "kinova3f")
HELD_OUT_HANDS = ("shadow", "barrett")
SIZE_RANGE = (0.05, 0.40)  # m, paper: scaled to 0.05-0.4
MAX_CONTACTS = 5
MAX_DOF = 24
MANIFEST = "manifest.json"


@dataclass
class DataConfig:
    """Data-set settings (recorded in the manifest)."""

    objects: int = 64
    seed: int = 0
    objects_per_shard: int = 4
    test_fraction: float = 0.15  # of objects (by id)
    unseen_motion_fraction: float = 0.15  # of train-object examples held out as test_so
    articulated_fraction: float = 0.2
    hands: tuple[str, ...] = TRAIN_HANDS
    held_out_hands: tuple[str, ...] = HELD_OUT_HANDS
    grasps_per_job: int = 6
    examples_per_grasp: int = 4
    targeted_per_grasp: int = 0  # examples of a chosen task (lift, push, turn: `research.data.targeted`) per grasp
    palms: int = 16
    max_set: int = 32  # valid grasps kept per example (grasp_sets.MAX_SET; a denser sampling has more to keep)
    num_points: int = 2048
    kinds: tuple[str, ...] = ()  # empty: every kind of manifoundation.core.objects
    test_objects_only: bool = False  # label test objects only (the evaluation set, ~7x faster); shards keep all ids
    physics: str = "off"  # "closure": only sampled grasps that hold in the six-push test label (physics_labels)
    closure_mu: float | None = None  # sample grasps aiming for force closure at this μ (sampling.sample_grasps)

    def to_dict(self) -> dict[str, Any]:
        return {k: list(v) if isinstance(v, tuple) else v for k, v in asdict(self).items()}


def object_split(object_id: str, test_fraction: float) -> str:
    """``"test"`` or ``"train"``, fixed by the object's id."""
    h = int(hashlib.sha1(object_id.encode()).hexdigest()[:8], 16) % 1000
    return "test" if h < 1000 * test_fraction else "train"


def make_dataset_object(cfg: DataConfig, i: int) -> ProceduralObject:
    """Object ``i`` of the data set."""
    from manifoundation.core.objects import OBJECT_KINDS, make_object

    kinds = cfg.kinds or OBJECT_KINDS
    rng = np.random.default_rng([cfg.seed, i])
    size = float(rng.uniform(*SIZE_RANGE))
    return make_object(kinds[i % len(kinds)], size, int(rng.integers(2**31)), cfg.num_points)


def available_hands(names: tuple[str, ...]) -> list[str]:
    """The names in ``names`` that the hand registry knows, old names (aliases) included; others are skipped
    (``mani-lab data generate`` refuses them by name first)."""
    from manifoundation.core.robots import list_hands

    known = set(list_hands(aliases=True))
    return [n for n in names if n in known]


@dataclass
class ShardResult:
    index: int
    file: str
    objects: int
    examples: int
    counts: dict[str, int] = field(default_factory=dict)
    seconds: float = 0.0


def run_shard(cfg: DataConfig, index: int, out_dir: str) -> ShardResult:
    """Generate and write shard ``index``."""
    import torch

    from manifoundation.core.robots import get_hand
    from research.data.checks import ObjectField
    from research.data.examples import ObjectInfo, make_example
    from research.data.physics_labels import held_grasps
    from research.data.sampling import sample_grasps
    from research.data.targeted import make_targeted_example

    torch.set_num_threads(1)
    t0 = time.perf_counter()
    first = index * cfg.objects_per_shard
    last = min(cfg.objects, first + cfg.objects_per_shard)
    hands = available_hands(cfg.hands)
    held = available_hands(cfg.held_out_hands)
    all_hands = list(cfg.hands) + list(cfg.held_out_hands)
    objs: dict[str, list[Any]] = {
        k: [] for k in ("ids", "kinds", "points", "normals", "scale", "centre", "mass", "inertia", "length", "split")
    }
    ex: dict[str, list[Any]] = {}
    counts: Counter[str] = Counter()
    for oi, i in enumerate(range(first, last)):
        obj = make_dataset_object(cfg, i)
        split = object_split(obj.id, cfg.test_fraction)
        info = ObjectInfo.from_object(obj)
        values = (obj.id, obj.kind, obj.points, obj.normals, info.scale, info.centre, info.mass, info.inertia,
                  info.length, split)  # fmt: skip
        for key, val in zip(objs, values, strict=True):  # objs' keys in this order
            objs[key].append(val)
        if cfg.test_objects_only and split != "test":
            continue  # the object stays in the shard (global indices unchanged), without examples
        fieldobj = ObjectField(obj.mesh, seed=obj.seed)
        for hand_name in hands + (held if split == "test" else []):
            rng = np.random.default_rng([cfg.seed, i, all_hands.index(hand_name)])
            try:
                hand = get_hand(hand_name)
                grasps = sample_grasps(hand, fieldobj, obj.size, rng, palms=cfg.palms, max_grasps=cfg.grasps_per_job,
                                       closure_mu=cfg.closure_mu)  # fmt: skip
            except Exception as exc:  # a hand under construction must not kill a long run; counted
                counts[f"errors/{hand_name}/{type(exc).__name__}"] += 1
                continue
            if cfg.physics == "closure":
                judged = held_grasps(hand, grasps, obj.mesh)
                counts[f"physics/tested/{hand_name}"] += len(grasps)
                counts[f"physics/held/{hand_name}"] += len(judged.held)
                grasps = judged.held
            for g in grasps:
                for nth in range(cfg.examples_per_grasp + cfg.targeted_per_grasp):
                    if hand_name in held or split == "test":
                        which, unseen = "test_uo" if split == "test" else "test_so", True
                    elif rng.random() < cfg.unseen_motion_fraction:
                        which, unseen = "test_so", True
                    else:
                        which, unseen = "train", False
                    if nth < cfg.examples_per_grasp:
                        articulated = bool(rng.random() < cfg.articulated_fraction)
                        e = make_example(info, g.contacts, g.normals, rng, want_unseen=unseen, articulated=articulated)
                    else:
                        e = make_targeted_example(info, g.contacts, g.normals, rng, want_unseen=unseen)
                    if e is None:
                        continue
                    m = len(g.contacts)
                    row = {
                        "obj_index": oi,
                        "hand": hand_name,
                        "split": which,
                        "friction": e["friction"],
                        "motion": e["motion"].astype(np.float32),
                        "heat": e["heat"].astype(np.float32),
                        "force_map": e["force_map"].astype(np.float32),
                        "mask": e["mask"],
                        "contacts": _pad(g.contacts, MAX_CONTACTS),
                        "contact_normals": _pad(g.normals, MAX_CONTACTS),
                        "forces": _pad(e["forces"], MAX_CONTACTS),
                        "num_contacts": m,
                        "palm_pos": g.palm_pos,
                        "palm_quat": g.palm_quat,
                        "q": _pad(g.q[:, None], MAX_DOF)[:, 0],
                        "articulated": e["articulated"],
                        "joint_type": e["joint_type"],
                        "joint_axis": e["joint_axis"],
                        "joint_origin": e["joint_origin"],
                        "joint_amount": e.get("joint_amount", 0.0),
                        "delta_x": e["delta_x"],
                        "delta_theta": e["delta_theta"],
                    }
                    for k, v in row.items():
                        ex.setdefault(k, []).append(v)
                    counts[f"{which}/{hand_name}"] += 1
                    counts[which] += 1
                    if e["articulated"]:
                        counts["articulated"] += 1
    name = f"shard-{index:05d}.npz"
    arrays: dict[str, np.ndarray] = {f"object_{k}": np.asarray(v) for k, v in objs.items()}
    n_ex = len(ex.get("hand", []))
    for k, v in ex.items():
        arrays[k] = np.asarray(v)
    arrays["num_examples"] = np.asarray(n_ex)
    arrays["max_set"] = np.asarray(cfg.max_set)
    tmp = Path(out_dir) / (name + ".tmp.npz")
    np.savez_compressed(tmp, **arrays)  # type: ignore[arg-type]
    os.replace(tmp, Path(out_dir) / name)
    if n_ex:  # the grasp sets (one linear programme per example and grasp) in this worker, not at training time
        from research.data.dataset import cached_grasp_sets

        cached_grasp_sets(Path(out_dir) / name, arrays)
    return ShardResult(index, name, last - first, n_ex, dict(counts), time.perf_counter() - t0)


def _pad(a: np.ndarray, n: int) -> np.ndarray:
    out = np.full((n, a.shape[1]), np.nan)
    out[: len(a)] = a
    return out


ShardJob = tuple[DataConfig, int, str]  # (configuration, shard index, output directory)
ShardRunner = Callable[[list[ShardJob]], Iterator[ShardResult]]  # shards made, files in place; default: run_jobs


def _run_shard_star(args: ShardJob) -> ShardResult:
    return run_shard(*args)


def read_manifest(out_dir: str | Path) -> dict[str, Any]:
    """The manifest of a data directory (empty skeleton when absent)."""
    path = Path(out_dir) / MANIFEST
    if path.is_file():
        manifest: dict[str, Any] = json.loads(path.read_text())
        return manifest
    return {"config": None, "shards": {}}


def generate(cfg: DataConfig, out_dir: str | Path, workers: int = 1, progress: bool = True,
             runner: ShardRunner | None = None) -> dict[str, Any]:  # fmt: skip
    """Generate (or resume) a data set in ``out_dir`` by ``runner``; returns the manifest (+ ``lost_shards``).

    Raises:
        ValueError: ``out_dir`` holds a data set made with a different configuration.
    """
    from tqdm import tqdm

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    manifest = read_manifest(out)
    made = manifest["config"]  # settings added since the data set was made take their defaults
    if made is not None and {**DataConfig().to_dict(), **made} != cfg.to_dict():
        raise ValueError(f"{out} holds a data set with another configuration; use a new directory")
    manifest["config"] = cfg.to_dict()
    manifest["hands_available"] = available_hands(cfg.hands) + available_hands(cfg.held_out_hands)
    n_shards = -(-cfg.objects // cfg.objects_per_shard)
    todo = [
        k
        for k in range(n_shards)
        if str(k) not in manifest["shards"] or not (out / manifest["shards"][str(k)]["file"]).is_file()
    ]
    t0 = time.perf_counter()
    done_examples = 0
    bar = tqdm(total=n_shards, initial=n_shards - len(todo), unit="shard", disable=not progress, smoothing=0.1)
    jobs: list[ShardJob] = [(cfg, k, str(out)) for k in todo]

    def record(r: ShardResult) -> None:
        nonlocal done_examples
        manifest["shards"][str(r.index)] = asdict(r)
        done_examples += r.examples
        rate = done_examples / max(time.perf_counter() - t0, 1e-9)
        manifest["totals"] = _totals(manifest)
        manifest["last_rate_examples_per_s"] = rate
        write_manifest(out / MANIFEST, manifest)
        bar.update(1)
        bar.set_postfix(examples=manifest["totals"]["examples"], ex_per_s=f"{rate:.2f}")

    for r in (runner or (lambda js: run_jobs(_run_shard_star, js, workers)))(jobs):
        record(r)
    bar.close()
    manifest["totals"] = _totals(manifest)
    manifest["lost_shards"] = [k for k in todo if str(k) not in manifest["shards"]]
    write_manifest(out / MANIFEST, manifest)
    return manifest


def _totals(manifest: dict[str, Any]) -> dict[str, Any]:
    counts: Counter[str] = Counter()
    secs = 0.0
    for s in manifest["shards"].values():
        counts.update(s["counts"])
        secs += s["seconds"]
    ex = sum(s["examples"] for s in manifest["shards"].values())
    return {
        "examples": ex,
        "shards": len(manifest["shards"]),
        "counts": dict(counts),
        "worker_seconds": secs,
        "examples_per_worker_s": ex / secs if secs else 0.0,
    }
