"""The refinement evaluation (paper Table II, docs/evaluation.md) as a library; `mani-lab eval refine` drives it.


Protocol, per object and grasp:

1. Known-feasible ("ground-truth") palm pose, from one of two sources (``ground_truth``):

   * ``"sampled"`` (default, independent of the refinement under test): the data generator's hierarchical grasp
     sampling (`research.data.sampling.sample_grasps` on a `research.data.checks.ObjectField` of the object's mesh:
     palms facing the surface, per-finger IK onto it, combinations, rejection by exact geometry — every pad
     sphere on the surface, no penetration or self-collision beyond 1 mm). Sampling runs in rounds (at most
     ``SAMPLER_ROUNDS``, cached per hand and object so both modes see the same grasps); round r of object k
     samples ``SAMPLER_PALMS`` facing palms (``default_rng([seed, k, 1000 + r])``), then as many palms pinching
     an antipodal pair the hand spans, whose contacts pass the closure tests (``closure_mu``,
     `research.data.pinch`; ``default_rng([seed, k, 2000 + r])``) — the facing palms alone seldom give force
     closure on objects larger than the hand. The sampled grasps
     are taken in order and each is verified with `verify` (same cloud, mesh and μ as the trial). ``closure``
     mode keeps a grasp only when it passes `verify` for force closure (wrench residual < 1e-3 and Ferrari–Canny
     ε > 0 at μ); ``task`` mode keeps any grasp that passes the geometric tests, draws the target wrench from its
     contacts (step 2) and keeps it when it also passes `verify` for that task (else the next grasp). Grasp j of
     an object takes the first eligible sampled grasp after the one grasp j − 1 took. A grasp is "skipped"
     (``Report.skipped``) only when the sampler yields no eligible grasp within its rounds.
   * ``"refined"`` (the original protocol, kept for comparison; circular, since objects where our refinement
     fails are dropped): the palm faces the object centre from a random direction with a random roll about it,
     its rest fingertips centred on the object and then backed off until no palm/finger-body sphere touches
     (fingertips may start inside); refinement for force closure with the default settings; the first result
     that passes verification is the ground truth (up to ``attempts`` = 10 tries, else skipped). (Random
     contacts + §III-B-1 initialisation, tried first, gave feasible grasps 3× less often.)

2. Target: force closure (w = 0), or a task wrench that the ground-truth grasp can produce: random forces in the
   friction cones at its contacts, w = Σ G_i f_i, kept when the forces that give the unit wrench w/‖w‖ respect the
   normal bound (else resampled) — the paper's data generator does the same.
3. Start: the ground-truth palm moved back along its approach axis by ``retreat`` (paper and default: 30 cm),
   rotated about its origin by a random axis and an angle uniform in [0, 60°], moved by a random vector of length
   ≤ 5 cm; fingers at rest.
4. Run our refinement (`manifoundation.core.refine.strategy.refine_from_start`: approach alignment, SCP, restarts within
the
   100-iteration budget) and the direct-grasp baseline from the same start; verify both with exact geometry.

Times are CPU seconds of this process (`time.process_time`, torch on one thread): on a shared machine the wall
time also counts other processes' work. Ground-truth sampling is not timed.

Why one module: the protocol's steps (ground truth, perturbation, the two modes, the report) are one experiment and
share its seeds.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np
from scipy.spatial.transform import Rotation

from manifoundation.core.geometry.object import DEFAULT_FRICTION
from manifoundation.core.refine.baseline import direct_grasp
from manifoundation.core.refine.field import PointCloudField
from manifoundation.core.refine.grasp import grasp_maps, tangents
from manifoundation.core.refine.initialise import back_off, rest_geometry
from manifoundation.core.refine.refine import RefineConfig, refine
from manifoundation.core.refine.state import HandPose
from manifoundation.core.refine.strategy import refine_from_start
from manifoundation.core.refine.verify import Verification, verify
from manifoundation.core.refine.wrench import WrenchTask, characteristic_length, closure_task, rigid_task

if TYPE_CHECKING:
    from manifoundation.core.robots.hand import Hand

DEFAULT_MU = DEFAULT_FRICTION
GROUND_TRUTHS = ("sampled", "refined")
SAMPLER_PALMS = 16  # palms per sampling round
SAMPLER_MAX_GRASPS = 16  # feasible grasps kept per round
SAMPLER_ROUNDS = 6  # rounds per (hand, object) at most
GEOMETRIC_FAILURES = ("tip_distance", "penetration", "self_collision")


@dataclass
class Trial:
    """One grasp: ours and the baseline."""

    object_id: str
    grasp: int
    success: bool
    seconds: float
    iterations: int
    reason: str
    failures: list[str]
    baseline_success: bool
    baseline_seconds: float
    baseline_failures: list[str]


@dataclass
class Report:
    """All trials of one (hand, mode) run, plus skipped grasps (no feasible ground truth found)."""

    hand: str
    mode: str
    trials: list[Trial] = field(default_factory=list)
    skipped: int = 0
    ground_truth: str = "sampled"

    def summary(self) -> dict[str, float]:
        """Success rates (%), median / p90 seconds per grasp, median iterations, for ours and the baseline."""
        if not self.trials:
            return {"n": 0, "skipped": self.skipped}
        sec = np.array([t.seconds for t in self.trials])
        bsec = np.array([t.baseline_seconds for t in self.trials])
        return {
            "n": len(self.trials),
            "skipped": self.skipped,
            "success": 100.0 * float(np.mean([t.success for t in self.trials])),
            "median_s": float(np.median(sec)),
            "p90_s": float(np.percentile(sec, 90)),
            "median_iterations": float(np.median([t.iterations for t in self.trials])),
            "baseline_success": 100.0 * float(np.mean([t.baseline_success for t in self.trials])),
            "baseline_median_s": float(np.median(bsec)),
            "baseline_p90_s": float(np.percentile(bsec, 90)),
        }


def feasible_grasp(
    hand: Hand, cloud: PointCloudField, mesh: Any, task: WrenchTask, mu: float, rng: np.random.Generator,
    attempts: int = 10, config: RefineConfig | None = None,
) -> HandPose | None:
    """A verified force-closure pose from random contacts (protocol step 1), or None."""
    rest = rest_geometry(hand)
    for _ in range(attempts):
        res = refine(hand, cloud, task, approach_start(hand, cloud, task.centre, rng, rest), mu, config)
        if res.converged and verify(hand, res.pose, cloud, task, mu, mesh).success:
            return res.pose
    return None


@dataclass
class SampledCandidate:
    """A sampled grasp as a pose and its verification for force closure (the geometric tests included)."""

    pose: HandPose
    verification: Verification

    @property
    def geometric_ok(self) -> bool:
        """Pad spheres on the surface, no penetration, no self-collision (what every mode needs)."""
        return not any(f in GEOMETRIC_FAILURES for f in self.verification.failures)

    @property
    def closure_ok(self) -> bool:
        """Passes `verify` for force closure (ε > 0 and a closure residual within tolerance)."""
        return self.verification.success


class SampledGroundTruth:
    """Protocol step 1, ``"sampled"``: the data generator's grasps on one object, sampled lazily in rounds.

    ``candidate(i)`` is the i-th sampled grasp (over all rounds, in order), verified for force closure; None once
    ``rounds`` rounds are spent. Round r draws from ``default_rng([seed, index, 1000 + r])``, so the sequence
    depends only on the seed, the object and the hand.
    """

    def __init__(
        self, hand: Hand, obj: Any, cloud: PointCloudField, closure: WrenchTask, mu: float, seed: int, index: int,
        rounds: int = SAMPLER_ROUNDS, palms: int = SAMPLER_PALMS, max_grasps: int = SAMPLER_MAX_GRASPS,
    ) -> None:
        self.hand, self.obj, self.cloud, self.closure, self.mu = hand, obj, cloud, closure, mu
        self.seed, self.index, self.rounds, self.palms, self.max_grasps = seed, index, rounds, palms, max_grasps
        self.candidates: list[SampledCandidate] = []
        self.rounds_done = 0
        self._field: Any = None

    def _sample_round(self) -> None:
        from research.data.checks import ObjectField
        from research.data.sampling import sample_grasps

        if self._field is None:
            self._field = ObjectField(self.obj.mesh, seed=int(getattr(self.obj, "seed", 0)))
        size = float(getattr(self.obj, "size", np.ptp(self.obj.points, axis=0).max()))
        r = self.rounds_done
        self.rounds_done += 1
        facing = sample_grasps(self.hand, self._field, size, np.random.default_rng([self.seed, self.index, 1000 + r]),
                               palms=self.palms, max_grasps=self.max_grasps)
        pinching = sample_grasps(self.hand, self._field, size, np.random.default_rng([self.seed, self.index, 2000 + r]),
                                 palms=self.palms, max_grasps=self.max_grasps, closure_mu=self.mu)
        for g in facing + pinching:
            pose = HandPose(np.asarray(g.palm_pos, np.float64), np.asarray(g.palm_quat, np.float64),
                            np.asarray(g.q, np.float64))
            ver = verify(self.hand, pose, self.cloud, self.closure, self.mu, self.obj.mesh)
            self.candidates.append(SampledCandidate(pose, ver))

    def candidate(self, i: int) -> SampledCandidate | None:
        """The i-th sampled grasp, sampling further rounds as needed; None when the rounds are spent."""
        while i >= len(self.candidates) and self.rounds_done < self.rounds:
            self._sample_round()
        return self.candidates[i] if i < len(self.candidates) else None


def sampled_ground_truth(
    sampler: SampledGroundTruth, mode: str, start: int, rng: np.random.Generator,
) -> tuple[HandPose, WrenchTask, int] | None:
    """The first eligible sampled grasp at index ≥ ``start`` for ``mode``, its task, and the index after it.

    Closure: a grasp that passes `verify` for force closure. Task: a geometrically valid grasp with a target
    wrench drawn from its contacts (`feasible_wrench`) that it passes `verify` for. None: the sampler is spent.
    """
    i = start
    while (cand := sampler.candidate(i)) is not None:
        i += 1
        if mode == "closure":
            if cand.closure_ok:
                return cand.pose, sampler.closure, i
            continue
        if not cand.geometric_ok:
            continue
        ver = cand.verification
        c, length = sampler.closure.centre, sampler.closure.length
        w = feasible_wrench(ver.tips, ver.normals, sampler.mu, c, length, rng)
        task = rigid_task(np.concatenate([w[:3], w[3:] * length]), c, length)
        if verify(sampler.hand, cand.pose, sampler.cloud, task, sampler.mu, sampler.obj.mesh,
                  collisions=False).success:
            return cand.pose, task, i
    return None


def approach_start(
    hand: Hand, cloud: PointCloudField, centre: np.ndarray, rng: np.random.Generator, rest: Any = None
) -> HandPose:
    """Palm facing ``centre`` from a random direction and roll, backed off until its body spheres clear."""
    rest = rest or rest_geometry(hand)
    axis = np.asarray(hand.approach_axis, dtype=np.float64)
    d = rng.normal(size=3)
    d /= np.linalg.norm(d)
    r0 = Rotation.align_vectors([d], [axis])[0]
    rot = (Rotation.from_rotvec(d * rng.uniform(0, 2 * np.pi)) * r0).as_matrix()
    t = centre - rot @ rest.tips.mean(axis=0)
    t = back_off(rot, t, rest, np.asarray(hand.sphere_radii), cloud, d, max_distance=0.3)
    quat = Rotation.from_matrix(rot).as_quat()[[3, 0, 1, 2]]
    return HandPose(t, quat, np.asarray(hand.rest, dtype=np.float64).copy())


def feasible_wrench(
    tips: np.ndarray, normals: np.ndarray, mu: float, centre: np.ndarray, length: float,
    rng: np.random.Generator, max_normal_force: float = 1.0, tries: int = 200,
) -> np.ndarray:
    """A unit scaled wrench the contacts can produce within the force bound (protocol step 2)."""
    t1, t2 = tangents(normals)
    g = grasp_maps(tips, centre, length)
    best, best_fn = None, np.inf
    for _ in range(tries):
        fn = rng.uniform(0, 1, size=len(tips))
        ang = rng.uniform(0, 2 * np.pi, size=len(tips))
        ft = mu * rng.uniform(0, 1, size=len(tips)) * fn
        f = -normals * fn[:, None] + (np.cos(ang) * ft)[:, None] * t1 + (np.sin(ang) * ft)[:, None] * t2
        w = np.einsum("mij,mj->i", g, f)
        needed = fn.max() / np.linalg.norm(w)
        if needed < best_fn:
            best, best_fn = w, needed
        if needed <= max_normal_force:
            break
    assert best is not None
    unit: np.ndarray = best / np.linalg.norm(best)
    return unit


def perturb(
    hand: Hand, pose: HandPose, rng: np.random.Generator, retreat: float = 0.30,
    max_angle_deg: float = 60.0, max_shift: float = 0.05,
) -> HandPose:
    """Protocol step 3: retreat along the approach axis, random rotation ≤ max angle, shift ≤ max_shift."""
    rot = Rotation.from_quat(pose.palm_quat[[1, 2, 3, 0]])
    approach = rot.apply(np.asarray(hand.approach_axis, dtype=np.float64))
    axis = rng.normal(size=3)
    axis /= np.linalg.norm(axis)
    turn = Rotation.from_rotvec(axis * np.deg2rad(rng.uniform(0, max_angle_deg)))
    shift = rng.normal(size=3)
    shift *= rng.uniform(0, max_shift) / np.linalg.norm(shift)
    quat = (turn * rot).as_quat()[[3, 0, 1, 2]]
    return HandPose(pose.palm_pos - approach * retreat + shift, quat, np.asarray(hand.rest, dtype=np.float64).copy())


def evaluate(
    hand: Hand,
    objects: Iterable[Any],
    mode: str,
    grasps: int,
    seed: int,
    mu: float = DEFAULT_MU,
    retreat: float = 0.30,
    config: RefineConfig | None = None,
    on_trial: Callable[[Trial | None], None] | None = None,
    ground_truth: str = "sampled",
    cache: dict[Any, SampledGroundTruth] | None = None,
    store: dict[Any, tuple[list[SampledCandidate], int]] | None = None,
) -> Report:
    """Run the protocol over ``objects`` (each with ``.id``, ``.points``, ``.normals``, ``.mesh``; ``.size`` and
    ``.seed`` are used by the sampler when present).

    ``ground_truth`` picks step 1's source (module doc). ``cache`` (a dict kept by the caller) shares the sampled
    grasps between the modes of one hand; ``store`` (a dict the caller may pickle, `mani-lab eval refine
    --ground-truth-cache`) keeps them across runs: its entries are restored, and updated after each object.
    ``on_trial`` is called after every grasp (with None for a skipped one),
    e.g. to advance a progress bar.
    """
    if mode not in ("task", "closure"):
        raise ValueError(f"mode must be 'task' or 'closure', got {mode!r}")
    if ground_truth not in GROUND_TRUTHS:
        raise ValueError(f"ground_truth must be one of {GROUND_TRUTHS}, got {ground_truth!r}")
    cache = {} if cache is None else cache
    report = Report(hand=hand.name, mode=mode, ground_truth=ground_truth)
    for k, obj in enumerate(objects):
        cloud = PointCloudField(obj.points, obj.normals)
        centre = np.zeros(3)  # procedural objects are centred on their centre of mass
        length = characteristic_length(obj.points, centre)
        closure = closure_task(centre, length)
        key = (hand.name, obj.id, seed, k, mu)
        if ground_truth == "sampled" and key not in cache:
            cache[key] = SampledGroundTruth(hand, obj, cloud, closure, mu, seed, k)
            if store is not None and key in store:
                cache[key].candidates, cache[key].rounds_done = list(store[key][0]), store[key][1]
        next_candidate = 0
        for j in range(grasps):
            rng = np.random.default_rng([seed, k, j])
            if ground_truth == "sampled":
                found = sampled_ground_truth(cache[key], mode, next_candidate, rng)
                if found is None:
                    report.skipped += 1
                    if on_trial:
                        on_trial(None)
                    continue
                gt, task, next_candidate = found
            else:
                refined = feasible_grasp(hand, cloud, obj.mesh, closure, mu, rng)
                if refined is None:
                    report.skipped += 1
                    if on_trial:
                        on_trial(None)
                    continue
                gt = refined
                if mode == "closure":
                    task = closure
                else:
                    import torch

                    with torch.no_grad():
                        tips = hand.fingertips(*gt.tensors())[0].numpy()
                    w = feasible_wrench(tips, cloud.surface_normal(tips), mu, centre, length, rng)
                    task = rigid_task(np.concatenate([w[:3], w[3:] * length]), centre, length)
            start = perturb(hand, gt, rng, retreat=retreat)
            t0 = time.process_time()
            res = refine_from_start(hand, cloud, task, start, mu, config, seed=j)
            seconds = time.process_time() - t0
            ver = verify(hand, res.pose, cloud, task, mu, obj.mesh)
            t0 = time.process_time()
            base_pose, _ = direct_grasp(hand, cloud, start, centre)
            base_s = time.process_time() - t0
            base = verify(hand, base_pose, cloud, task, mu, obj.mesh)
            trial = Trial(
                object_id=obj.id, grasp=j, success=ver.success, seconds=seconds, iterations=res.iterations,
                reason=res.reason, failures=ver.failures, baseline_success=base.success,
                baseline_seconds=base_s, baseline_failures=base.failures,
            )
            report.trials.append(trial)
            if on_trial:
                on_trial(trial)
        if store is not None and key in cache:
            store[key] = (cache[key].candidates, cache[key].rounds_done)
    return report
