"""The worker of `mani-lab bench pipeline`: rebuild each request from its spec, run it, time its stages, audit it.

It reads one JSON spec per line on stdin and writes one JSON record per line on stdout. It imports only what
every checkout has (`manifoundation.core.pipeline`, `research.audit`, `manifoundation.core.objects`,
`manifoundation.core.robots`), so the same file runs
against a reference checkout (``PYTHONPATH=REF``). The refinement's parts are timed by wrapping, in the modules
that call them, ``linearise`` (the local model), ``surface_contacts`` (its real-surface contact model),
``object_guards`` (that model's object-point guard rows; ``_object_guards`` in checkouts before it had its own
module) and ``solve_step`` (the SCP solve); a checkout without
one of them reports it as missing (NaN).
"""

from __future__ import annotations

import json
import sys
import time
from collections.abc import Callable
from functools import wraps
from typing import Any

import numpy as np

WRAPPED = {
    "linearise": ("manifoundation.core.refine.refine", "linearise"),
    "contacts": ("manifoundation.core.refine.state", "surface_contacts"),
    "guards": ("manifoundation.core.refine.contact", "object_guards|_object_guards"),
    "solve": ("manifoundation.core.refine.refine", "solve_step"),
}
"""part → (module, attribute) wrapped with a timer (the attribute the caller looks up at call time; ``a|b``: the
first of the names the module has)."""


class _Timers:
    """Accumulated seconds and calls per part, reset per request."""

    def __init__(self) -> None:
        self.seconds: dict[str, float] = {}
        self.calls: dict[str, int] = {}
        self.found: set[str] = set()
        self.originals: list[tuple[Any, str, Any]] = []

    def install(self) -> None:
        """Wrap the functions of `WRAPPED` (`uninstall` restores them)."""
        import importlib

        for part, (module, name) in WRAPPED.items():
            mod = importlib.import_module(module)
            name = next((n for n in name.split("|") if hasattr(mod, n)), "")  # the first name this checkout has
            fn = getattr(mod, name, None) if name else None
            if fn is None:
                continue
            self.originals.append((mod, name, fn))
            setattr(mod, name, self._wrap(part, fn))
            self.found.add(part)

    def uninstall(self) -> None:
        for mod, name, fn in reversed(self.originals):
            setattr(mod, name, fn)
        self.originals, self.found = [], set()

    def _wrap(self, part: str, fn: Callable[..., Any]) -> Callable[..., Any]:
        @wraps(fn)
        def timed(*args: Any, **kwargs: Any) -> Any:
            t0 = time.perf_counter()
            try:
                return fn(*args, **kwargs)
            finally:
                self.seconds[part] = self.seconds.get(part, 0.0) + time.perf_counter() - t0
                self.calls[part] = self.calls.get(part, 0) + 1

        return timed

    def take(self) -> dict[str, Any]:
        out = {p: (self.seconds.get(p, 0.0) if p in self.found else float("nan")) for p in WRAPPED}
        out.update({f"{p}_calls": self.calls.get(p, 0) for p in WRAPPED})
        self.seconds, self.calls = {}, {}
        return out


class _Objects:
    """The object sets, loaded once: (points (N, 3), normals (N, 3), mesh or None) by set and index."""

    def __init__(self) -> None:
        self.cache: dict[tuple[str, int, int, int], tuple[np.ndarray, np.ndarray, Any]] = {}
        self.third: list[Any] | None = None
        self.procedural: list[Any] | None = None

    def get(self, spec: dict[str, Any]) -> tuple[np.ndarray, np.ndarray, Any]:
        key = (spec["set"], int(spec["object"]), int(spec["seed"]), int(spec["points"]))
        if key not in self.cache:
            self.cache[key] = self._load(spec)
        return self.cache[key]

    def _load(self, spec: dict[str, Any]) -> tuple[np.ndarray, np.ndarray, Any]:
        i, seed = int(spec["object"]), int(spec["seed"])
        if spec["set"] == "box":
            data = np.load(spec["box"])
            return np.asarray(data["points"]), np.asarray(data["normals"]), None
        if spec["set"] == "procedural":
            from manifoundation.core.objects import object_set

            if self.procedural is None or len(self.procedural) <= i:
                self.procedural = object_set(max(i + 1, 18), seed=0)
            obj = self.procedural[i]
            return np.asarray(obj.points), np.asarray(obj.normals), obj.mesh
        if spec.get("path"):  # the file the spec names: the same object whatever this checkout's candidates
            from pathlib import Path

            from research.audit.objects import load_third_party

            named = load_third_party(str(spec["name"]), Path(spec["path"]))
            assert named is not None, spec["path"]
            points, normals = named.sample(int(spec["points"]), seed)
            return points, normals, named.mesh
        from research.audit import third_party_objects

        if self.third is None:
            self.third = third_party_objects()
        obj = self.third[i % len(self.third)]
        points, normals = obj.sample(int(spec["points"]), seed)
        return points, normals, obj.mesh


def _request(spec: dict[str, Any], objects: _Objects) -> tuple[Any, Any, np.ndarray, np.ndarray]:
    from manifoundation.core.pipeline import SynthesisInput, TaskInput
    from manifoundation.core.robots import get_hand

    points, normals, mesh = objects.get(spec)
    lift = np.array([0.0, 0.0, 0.05])
    task = TaskInput("force_closure") if spec["task"] == "closure" else TaskInput(
        "delta_pose", translation=lift, rotation=np.array([1.0, 0.0, 0.0, 0.0]))  # fmt: skip
    send = mesh is not None and spec["geometry"] == "mesh"
    inp = SynthesisInput(
        points=points, normals=normals, hand=get_hand(spec["hand"]), task=task, method=spec["method"],
        num_proposals=int(spec["proposals"]), seed=int(spec["seed"]), properties={"friction": 0.8},
        mesh_vertices=np.asarray(mesh.vertices) if send else None, mesh_faces=np.asarray(mesh.faces) if send else None,
        simulate=spec.get("simulate", "off"),
    )  # fmt: skip
    return inp, mesh, points, normals


def _audit(spec: dict[str, Any], out: Any, mesh: Any, points: np.ndarray, normals: np.ndarray) -> list[bool]:
    from research.audit import AuditedGrasp, audit_grasp

    lift = np.array([0.0, 0.0, 0.05])
    target = None if spec["task"] == "closure" else np.r_[lift / np.linalg.norm(lift), np.zeros(3)]
    passed = []
    for p in out.proposals:
        grasp = AuditedGrasp(p.contact_points, p.forces, p.fingertips, p.palm_position, p.palm_quaternion,
                             p.joint_names, p.joint_values)  # fmt: skip
        soft = 0.005 if len(grasp.fingertips) == 2 else 0.0
        report = audit_grasp(spec["hand"], grasp, mesh, points, normals, mu=0.8, target_wrench=target,
                             closure=spec["task"] == "closure", soft_finger=soft)  # fmt: skip
        passed.append(bool(report.passed))
    return passed


_PREDICTORS: dict[str, Any] = {}


def _predictor(spec: dict[str, Any]) -> Any:
    """The network of a "network" request (``spec["weights"]``, loaded once per worker), else None."""
    if spec["method"] != "network":
        return None
    path = str(spec["weights"])
    if path not in _PREDICTORS:
        from manifoundation.core.network import ContactPredictor

        _PREDICTORS[path] = ContactPredictor.from_checkpoint(path)
    return _PREDICTORS[path]


def run_one(spec: dict[str, Any], objects: _Objects, timers: _Timers) -> dict[str, Any]:
    """Run one request; its record: wall seconds, stage and part seconds, iterations, claims, audit, answers,
    where each proposal's contacts came from."""
    from manifoundation.core.pipeline import run_pipeline

    inp, mesh, points, normals = _request(spec, objects)
    predictor = _predictor(spec)
    timers.take()
    t0 = time.perf_counter()
    out = run_pipeline(inp, predictor=predictor)
    wall = time.perf_counter() - t0
    record: dict[str, Any] = {"wall": wall, "stages": {k: float(v) for k, v in out.timings.items()}}
    record.update(timers.take())
    record["iterations"] = int(sum(p.quality.iterations for p in out.proposals))
    # what the service calls verified: where the simulated test ran, only what also held
    record["success"] = [bool(p.quality.success) and (p.physics is None or bool(p.physics.success))
                         for p in out.proposals]  # fmt: skip
    record["answers"] = [np.concatenate([p.palm_position, p.palm_quaternion, p.joint_values]).tolist()
                         for p in out.proposals]  # fmt: skip
    record["sources"] = [str(getattr(p, "contact_source", "")) for p in out.proposals]
    record["audit"] = _audit(spec, out, mesh, points, normals) if spec["audit"] and mesh is not None else None
    return record


def serve() -> int:
    """The worker loop: a spec per stdin line → a record per stdout line (a spec with ``load_only`` only loads
    its object and answers ``{}``)."""
    import torch

    torch.set_num_threads(1)
    objects, timers = _Objects(), _Timers()
    timers.install()
    answer, sys.stdout = sys.stdout, sys.stderr  # stdout carries the records only
    for line in sys.stdin:
        if line.strip():
            spec = json.loads(line)
            if spec.get("load_only"):  # the batch mode's preload: the object's file read and sampled, no request
                objects.get(spec)
                answer.write("{}\n")
            else:
                answer.write(json.dumps(run_one(spec, objects, timers)) + "\n")
            answer.flush()
    return 0
