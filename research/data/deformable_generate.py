"""Seeded, resumable generation of deformable examples (`mani-lab data generate --materials cloth,rope,plasticine`).

Body ``i`` of material m in a data set of seed S has kind ``KINDS[m][i mod len]`` and seed
``default_rng([S, material index, i])``; its split (train/test) is fixed by its id like the rigid data's. Each
body is one file ``<out>/deformable/<material>-<i>.npz`` (written atomically) with its cloud and
``examples_per_body`` examples (`deformable_examples.make_example`, their rng ``default_rng([S, m, i, 1])``),
recorded in ``<out>/deformable/manifest.json``; a rerun skips recorded files (resume). Example splits: ``train``,
``test_so`` (train bodies, unseen motions), ``test_uo`` (test bodies, unseen motions); test bodies' seen-motion
examples are dropped, as the paper's test sets hold unseen motions only.
"""

from __future__ import annotations

import json
import os
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from manifoundation.core.deformable.body import DeformableBody
from manifoundation.core.deformable.materials import MATERIALS, STIFF_RANGES, sample_properties, sample_stiff_end
from manifoundation.core.deformable.shapes import KINDS, make_body
from manifoundation.core.deformable.slides import SET_NAMES
from research.data.runs import run_jobs, write_manifest

SUBDIR = "deformable"
MANIFEST = "manifest.json"
MAX_CONTACTS = 32
PROPERTY_KEYS = ("friction", "density", "stretch", "bending", "youngs_modulus", "poisson_ratio", "yield_stress")


@dataclass
class DeformableDataConfig:
    """Settings (recorded in the manifest)."""

    materials: tuple[str, ...] = MATERIALS
    bodies: int = 12  # per material
    examples_per_body: int = 4
    seed: int = 0
    test_fraction: float = 0.25
    verify_moving: bool = False  # cloth and rope labels: + the most-moved points when the simulator verifies them
    slides: float = 0.0  # cloth and rope: the fraction of examples that are slides (`make_slide_example`)
    stiff: bool = False  # properties drawn in `materials.STIFF_RANGES` (cards and sticks too)
    slide_margin: float = 0.0  # slides: labelled sets also reach a slide this long (× size; make_slide_example)
    stiff_ends: float = 0.0  # with `stiff`: this fraction of bodies draws its stiffnesses in one of `STIFF_ENDS`
    paired_ends: bool = False  # with `stiff`: bodies 2k, 2k+1 are one shape at the soft and the stiff end, same tasks

    def to_dict(self) -> dict[str, Any]:
        out = {k: list(v) if isinstance(v, tuple) else v for k, v in asdict(self).items()}
        for name, default in (("verify_moving", False), ("slides", 0.0), ("stiff", False), ("slide_margin", 0.0),
                              ("stiff_ends", 0.0), ("paired_ends", False)):
            if out[name] == default:  # data sets made before the option keep their manifests' configuration
                del out[name]
        return out


@dataclass
class BodyResult:
    material: str
    index: int
    file: str
    examples: int
    counts: dict[str, int] = field(default_factory=dict)
    seconds: float = 0.0


def dataset_body(cfg: DeformableDataConfig, material: str, i: int) -> DeformableBody:
    """Body ``i`` of ``material`` in the data set.

    With ``paired_ends``, bodies ``2k`` and ``2k + 1`` are body ``2k``'s shape, seed and other properties, with
    stiffnesses drawn in the soft and in the stiff end of `STIFF_ENDS` (cloth and rope)."""
    kinds = KINDS[material]
    shape = _shape_index(cfg, i)
    seed = int(np.random.default_rng([cfg.seed, MATERIALS.index(material), shape]).integers(2**31))
    body = make_body(material, kinds[shape % len(kinds)], seed)
    if not cfg.stiff:
        return body
    properties = sample_properties(material, np.random.default_rng([seed, 2]), STIFF_RANGES)
    if cfg.paired_ends:
        properties.update(sample_stiff_end(material, np.random.default_rng([seed, 3, i % 2]), i % 2))
    elif cfg.stiff_ends > 0:  # its own stream: bodies outside the ends keep the properties they had without it
        ends = np.random.default_rng([seed, 3])
        if ends.random() < cfg.stiff_ends:
            properties.update(sample_stiff_end(material, ends))
    return body.with_properties(properties)


def body_split(cfg: DeformableDataConfig, material: str, i: int) -> str:
    """Body ``i``'s object split (train/test), fixed by its id — a pair's by its first body's, so that one shape is
    never both trained on and tested."""
    from research.data.generate import object_split

    return object_split(dataset_body(cfg, material, _shape_index(cfg, i)).id, cfg.test_fraction)


def _shape_index(cfg: DeformableDataConfig, i: int) -> int:
    """The index whose shape, seed and tasks body ``i`` takes (``i`` itself unless the bodies come in pairs)."""
    return i - i % 2 if cfg.paired_ends else i


def run_body(cfg: DeformableDataConfig, material: str, i: int, out_dir: str) -> BodyResult:
    """Generate and write body ``i`` of ``material``."""
    from research.data.deformable_examples import make_example, make_slide_example
    t0 = time.perf_counter()
    body = dataset_body(cfg, material, i)
    split = body_split(cfg, material, i)
    stream = [cfg.seed, MATERIALS.index(material), _shape_index(cfg, i), 1]
    shared = None if cfg.paired_ends else np.random.default_rng(stream)
    rows: dict[str, list[Any]] = {}
    counts: dict[str, int] = {}
    for k in range(cfg.examples_per_body):
        # paired bodies take a stream per example: a pair's labels differ, and so may the draws they take
        rng = shared if shared is not None else np.random.default_rng([*stream, k])
        slide = cfg.slides > 0 and material in ("cloth", "rope") and rng.random() < cfg.slides  # no draw without
        if slide:
            ex = make_slide_example(body, rng, cfg.slide_margin)
        else:
            ex = make_example(body, rng, verify_moving=cfg.verify_moving)
        if ex is None:
            key = "slide_unreached" if slide else "unstable"
            counts[key] = counts.get(key, 0) + 1
            continue
        which = ("test_uo" if split == "test" else "test_so") if ex.unseen_motion else "train"
        if split == "test" and which == "train":
            continue
        if ex.margin_fallback:
            counts["slide_margin_fallback"] = counts.get("slide_margin_fallback", 0) + 1
        if ex.moving_checked:
            key = "moving_valid" if ex.label_sets > 1 else "moving_invalid"
            counts[key] = counts.get(key, 0) + 1
        h = len(ex.contacts)
        contacts = np.full(MAX_CONTACTS, -1, dtype=np.int64)
        motions = np.zeros((MAX_CONTACTS, 3))
        contacts[: min(h, MAX_CONTACTS)] = ex.contacts[:MAX_CONTACTS]
        motions[: min(h, MAX_CONTACTS)] = ex.contact_motions[:MAX_CONTACTS]
        for key, value in (("motion", ex.motion.astype(np.float32)), ("heat", ex.heat.astype(np.float32)),
                           ("motion_map", ex.motion_map.astype(np.float32)), ("mask", ex.mask),
                           ("contacts", contacts), ("contact_motions", motions), ("procedure", ex.procedure),
                           ("split", which), ("sim_seconds", ex.seconds), ("label_sets", ex.label_sets),
                           ("slide_shortfall", _or_nan(ex.set_shortfall)),
                           ("slide_shortfall_margin", _or_nan(ex.set_shortfall_margin))):  # fmt: skip
            rows.setdefault(key, []).append(value)
        counts[which] = counts.get(which, 0) + 1
    props = np.array([body.properties.get(k, np.nan) for k in PROPERTY_KEYS])
    arrays: dict[str, np.ndarray] = {
        "material": np.asarray(material), "kind": np.asarray(body.kind), "body_seed": np.asarray(body.seed),
        "body_id": np.asarray(body.id), "object_split": np.asarray(split), "points": body.points,
        "normals": body.normals, "property_names": np.asarray(PROPERTY_KEYS), "properties": props,
        "num_examples": np.asarray(len(rows.get("split", []))),
        **{k: np.asarray(v) for k, v in rows.items()},
    }  # fmt: skip
    name = f"{material}-{i:05d}.npz"
    tmp = Path(out_dir) / (name + ".tmp.npz")
    np.savez_compressed(tmp, **arrays)  # type: ignore[arg-type]
    os.replace(tmp, Path(out_dir) / name)
    return BodyResult(material, i, name, int(arrays["num_examples"]), counts, time.perf_counter() - t0)


def _or_nan(shortfalls: np.ndarray | None) -> np.ndarray:
    """A slide's per-set shortfalls (6,), or NaN for an example that is not a slide."""
    return np.full(len(SET_NAMES), np.nan) if shortfalls is None else shortfalls


def _run_star(args: tuple[DeformableDataConfig, str, int, str]) -> BodyResult:
    return run_body(*args)


def generate(cfg: DeformableDataConfig, out_dir: str | Path, workers: int = 1,
             progress: bool = True) -> dict[str, Any]:  # fmt: skip
    """Generate (or resume) the deformable part of a data set under ``out_dir/deformable``; returns the manifest.

    Raises:
        ValueError: the directory holds a data set of another configuration, or an unknown material.
    """
    from tqdm import tqdm

    for m in cfg.materials:
        if m not in MATERIALS:
            raise ValueError(f"materials: {m!r} is not deformable ({', '.join(MATERIALS)})")
    out = Path(out_dir) / SUBDIR
    out.mkdir(parents=True, exist_ok=True)
    path = out / MANIFEST
    manifest = json.loads(path.read_text()) if path.is_file() else {"config": None, "bodies": {}}
    if manifest["config"] is not None and manifest["config"] != cfg.to_dict():
        raise ValueError(f"{out} holds a data set with another configuration; use a new directory")
    manifest["config"] = cfg.to_dict()
    # Body by body across the materials, so that a run stopped early holds every material in like numbers.
    jobs = [(cfg, m, i, str(out)) for i in range(cfg.bodies) for m in cfg.materials
            if f"{m}-{i}" not in manifest["bodies"] or not (out / f"{m}-{i:05d}.npz").is_file()]  # fmt: skip
    total = len(cfg.materials) * cfg.bodies
    bar = tqdm(total=total, initial=total - len(jobs), unit="body", disable=not progress)
    t0, made = time.perf_counter(), 0

    def record(r: BodyResult) -> None:
        nonlocal made
        manifest["bodies"][f"{r.material}-{r.index}"] = asdict(r)
        made += r.examples
        rate = made / max(time.perf_counter() - t0, 1e-9)
        manifest["totals"] = _totals(manifest)
        manifest["last_rate_examples_per_s"] = rate
        write_manifest(path, manifest)
        bar.update(1)
        bar.set_postfix(examples=manifest["totals"]["examples"], ex_per_s=f"{rate:.2f}")

    for r in run_jobs(_run_star, jobs, workers):
        record(r)
    bar.close()
    manifest["totals"] = _totals(manifest)
    return manifest


def _totals(manifest: dict[str, Any]) -> dict[str, Any]:
    counts: dict[str, int] = {}
    for b in manifest["bodies"].values():
        for k, v in b["counts"].items():
            key = f"{b['material']}/{k}"
            counts[key] = counts.get(key, 0) + v
    secs = sum(b["seconds"] for b in manifest["bodies"].values())
    ex = sum(b["examples"] for b in manifest["bodies"].values())
    return {"examples": ex, "bodies": len(manifest["bodies"]), "counts": counts, "worker_seconds": secs,
            "examples_per_worker_s": ex / secs if secs else 0.0}  # fmt: skip


def load_body_file(path: str | Path) -> dict[str, np.ndarray]:
    """The arrays of one body file (strings as numpy str arrays; no pickles)."""
    with np.load(path, allow_pickle=False) as f:
        return {k: f[k] for k in f.files}
