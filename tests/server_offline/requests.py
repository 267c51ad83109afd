"""Small real request files for the offline tests: a sphere's points, panda_gripper, seeds 0..n-1."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from manifoundation.contract import SynthesisRequest, SynthesisResult
from manifoundation.contract.codec import dump_model, unpack

STAGED = "research.staged_pipeline:StagedPipeline"


def request(seed: int, max_iterations: int = 3, **options: object) -> SynthesisRequest:
    """A force-closure request on a 3 cm sphere of 64 points for panda_gripper."""
    normals = np.random.default_rng(0).normal(size=(64, 3))
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    return SynthesisRequest.model_validate({
        "object": {"points": 0.03 * normals, "normals": normals}, "task": {"kind": "force_closure"},
        "robot": {"name": "panda_gripper"}, "options": {"seed": seed, "max_iterations": max_iterations, **options},
    })  # fmt: skip


def write_requests(directory: Path, count: int, jsonl_from: int | None = None, **options: object) -> list[str]:
    """``count`` requests (seeds 0..count-1): even seeds as ``rNNNN.json``, odd as ``rNNNN.msgpack``, and from
    ``jsonl_from`` on as lines of ``many.jsonl``; returns the item ids in file-name order."""
    directory.mkdir(parents=True, exist_ok=True)
    ids, lines = [], []
    for seed in range(count):
        r = request(seed, **options)
        if jsonl_from is not None and seed >= jsonl_from:
            lines.append(r.model_dump_json(exclude_none=True))
            continue
        suffix = ".json" if seed % 2 == 0 else ".msgpack"
        (directory / f"r{seed:04d}{suffix}").write_bytes(dump_model(r, "application/" + suffix[1:]))
        ids.append(f"r{seed:04d}")
    if lines:
        (directory / "many.jsonl").write_text("\n".join(lines) + "\n")
        ids = [f"many-{n:06d}" for n in range(1, len(lines) + 1)] + ids
    return ids


def results(directory: Path) -> dict[str, dict[str, object]]:
    """Every result of an output directory by item id, timings left out: a success's `SynthesisResult` as a dict,
    a failure's error body."""
    out: dict[str, dict[str, object]] = {}
    for path in directory.glob("*.msgpack"):
        result = SynthesisResult.model_validate(unpack(path.read_bytes()))
        out[path.name.removesuffix(".msgpack")] = result.model_dump(mode="json", exclude={"timings"})
    for path in directory.glob("*.error.json"):
        body = json.loads(path.read_text())
        out[path.name.removesuffix(".error.json")] = {k: v for k, v in body.items() if k != "timings"}
    return out
