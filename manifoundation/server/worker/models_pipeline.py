"""`ModelsPipeline`: the worker's default `Pipeline`, the science of `models` (network → selection →

initialisation → refinement → verification).

Loaded once per worker process: the network from ``weights_dir`` (default ``manifoundation/core/weights``) when a
checkpoint is there (``model_loaded``), and the built-in hands (published as the robot catalogue). Without weights, jobs
whose method needs the network ("network", or "auto" without contacts) fail with a `ModelUnavailable` error;
"contacts", "direct_grasp" and "random_contacts" run end to end. Jobs run one at a time (per-job progress and
cancellation); with ``batch_network=True`` the network-method jobs of a micro-batch share one network call. A plan
job runs `manifoundation.core.planning.plan_manipulation` (every step through the same synthesis pipeline and
verification as a single request), its progress by stage: repair, planning (segments), contacts (steps).
"""

from __future__ import annotations

import contextlib
import hashlib
import logging
import time
from pathlib import Path
from typing import TYPE_CHECKING, Any

from manifoundation.contract import ErrorBody, ErrorType, RobotIn, RobotPublic, RobotRegister, Stage
from manifoundation.server.queue.records import cancelled_error
from manifoundation.server.worker.pipeline import (
    CancelFn,
    JobInput,
    Outcome,
    PlanJob,
    PlanOutcome,
    PlanProgressFn,
    ProgressFn,
    error_from_exception,
)

if TYPE_CHECKING:
    from manifoundation.core.pipeline.object_cache import LeastRecentlyUsed
    from manifoundation.core.robots.hand import Hand

log = logging.getLogger("manifoundation.server.worker.models_pipeline")
_HAND_CACHE = 32


class ModelsPipeline:
    """The models pipeline behind the worker's `Pipeline` protocol (see module doc)."""

    def __init__(
        self,
        weights_dir: str | None = None,
        threads: int = 1,
        batch_network: bool = False,
        hands: list[str] | None = None,
        object_cache: bool = True,
    ) -> None:
        """
        Args:
            weights_dir: checkpoint directory (or a directory of them); default ``manifoundation/core/weights``.
            threads: torch threads of this process (1: one worker process per core).
            batch_network: share one network call among a micro-batch's network jobs.
            hands: built-in hands to load and publish (default: all).
            object_cache: keep objects' prepared geometry for later jobs sending the same bytes (≤ 32 MB, the
                same answers; keyed by content alone: manifoundation/server/worker/README.md); False prepares every job
                afresh.
        """
        import torch

        import manifoundation.core
        from manifoundation.core.pipeline.object_cache import LeastRecentlyUsed, ObjectCache
        from manifoundation.core.robots import get_hand, list_hands

        self.objects = ObjectCache(enabled=object_cache)

        torch.set_num_threads(max(1, threads))
        self.batch_network = batch_network
        self.predictor = self._load(
            Path(weights_dir) if weights_dir else Path(manifoundation.core.__file__).parent / "weights"
        )
        self.model_loaded = self.predictor is not None
        card = getattr(self.predictor, "card", None)
        self.model_version: str | None = f"{card.config_name}-{card.version}" if card else None
        self._hands: LeastRecentlyUsed[Any] = LeastRecentlyUsed(_HAND_CACHE)  # user hands, by content
        self._builtin = {name: get_hand(name) for name in (hands if hands is not None else list_hands(aliases=True))}
        from manifoundation.core.compiled import warm_up

        log.info("compiled loops ready in %.2f s", warm_up())

    @staticmethod
    def _load(path: Path) -> Any | None:
        if not path.is_dir():
            log.info("no model weights at %s: method 'network' unavailable", path)
            return None
        from manifoundation.core.network.inference import ContactPredictor

        candidates = [path, *sorted(p for p in path.iterdir() if p.is_dir())]
        for candidate in candidates:
            try:
                predictor = ContactPredictor.from_checkpoint(candidate)
            except Exception as exc:
                log.debug("no checkpoint at %s: %s", candidate, exc)
                continue
            log.info("model loaded from %s", candidate)
            return predictor
        log.warning("no loadable checkpoint under %s: method 'network' unavailable", path)
        return None

    # ---- robots ----------------------------------------------------------------------------------------------
    def robots(self) -> list[RobotPublic]:
        from manifoundation.core.robots.registry import ALIASES

        return [
            _public(
                hand,
                name,
                builtin=True,
                source=f"built-in, alias of {ALIASES[name]}" if name in ALIASES else "built-in",
            )
            for name, hand in self._builtin.items()
        ]

    def validate_robot(self, robot: RobotRegister) -> RobotPublic:
        from manifoundation.server.worker.user_robots import robot_public

        return robot_public(self._registered(robot), robot)

    def _registered(self, robot: RobotRegister) -> Any:
        """The `HandBuild` of a registered hand (URDF/MJCF, archive with meshes, palm cut), cached by content."""
        from manifoundation.contract.codec import pack
        from manifoundation.core.robots import HandLoadError
        from manifoundation.server.worker.user_robots import build_robot

        key = hashlib.blake2b(pack(robot.model_dump(mode="python", exclude_none=True)), digest_size=16).digest()

        def build() -> Any:
            try:
                return build_robot(robot)
            except HandLoadError as exc:  # named by the field that carried the description
                source = "archive" if robot.archive is not None else "urdf" if robot.urdf is not None else "mjcf"
                raise HandLoadError(f"{source}: {exc}") from exc

        return self._hands.get(key, build)

    def _user_hand(self, name: str, urdf: str, fingertips: list[str], offsets: Any) -> Any:
        from manifoundation.core.robots import HandLoadError, load_hand

        key = hashlib.blake2b(f"{name}\0{urdf}\0{fingertips}\0{offsets}".encode(), digest_size=16).digest()

        def build() -> Any:
            try:
                return load_hand(urdf.encode(), fingertips=fingertips, tip_offsets=offsets, name=name)
            except HandLoadError as exc:
                raise HandLoadError(f"urdf: {exc}") from exc

        return self._hands.get(key, build)

    def _hand(self, robot: RobotIn | None, registered: RobotRegister | None) -> Any:
        """The hand a request's ``robot`` names (``registered``: the user's registration it names, if any)."""
        if robot is None:  # a deformable's contacts for any gripper: the network sees the hand of its data
            from manifoundation.core.pipeline.deformable import DEFORMABLE_HAND
            from manifoundation.core.robots import get_hand

            return self._builtin.get(DEFORMABLE_HAND) or get_hand(DEFORMABLE_HAND)
        if robot.urdf is not None:
            return self._user_hand("inline", robot.urdf, robot.fingertips or [], robot.tip_offsets)
        if robot.name in self._builtin:
            return self._builtin[robot.name]
        if registered is not None:
            return self._registered(registered).hand
        from manifoundation.core.errors import UnknownHand

        raise UnknownHand(f"robot.name: unknown hand {robot.name!r}; built-in: {', '.join(self._builtin)}")

    # ---- jobs ------------------------------------------------------------------------------------------------
    def _prepare(self, job: JobInput) -> tuple[Any, Any]:
        """The job's hand and core input; raises `InvalidInput` for what the loaded model cannot serve."""
        from manifoundation.core.errors import InvalidInput
        from manifoundation.server.worker.convert import method_of, to_input

        material = job.request.object.material.value
        card = getattr(self.predictor, "card", None)
        if material in ("cloth", "rope", "plasticine") and job.request.task.kind in ("point_motion", "target_points"):
            # deformables' contacts + motions: the network's answer as it is (manifoundation.core.pipeline.deformable)
            card = None
        if method_of(job.request) == "network" and card is not None and material not in (card.materials or [material]):
            raise InvalidInput(
                f"object.material: '{material}' is not supported by the loaded model "
                f"{self.model_version} (trained on: {', '.join(card.materials)}); "
                "use options.method 'contacts', 'random_contacts' or 'direct_grasp'"
            )
        hand = self._hand(job.request.robot, job.robot)
        return hand, to_input(job.request, hand, job.deadline)

    def run(self, jobs: list[JobInput], progress: ProgressFn, should_cancel: CancelFn) -> list[Outcome]:
        if self.batch_network and len(jobs) > 1:
            return self._run_batched(jobs, progress, should_cancel)
        return [self._run_one(job, progress, should_cancel) for job in jobs]

    def _run_one(self, job: JobInput, progress: ProgressFn, should_cancel: CancelFn) -> Outcome:
        from manifoundation.core.errors import ScienceError
        from manifoundation.core.pipeline import run_pipeline
        from manifoundation.server.worker.convert import to_result

        try:
            hand, inp = self._prepare(job)
            out = run_pipeline(inp, self.predictor, _reporter(job, progress), lambda: should_cancel(job.id),
                               cache=self.objects)
        except ScienceError as exc:
            return error_from_exception(exc)
        return to_result(out, job.request, self.model_version or "none", hand)

    def _run_batched(self, jobs: list[JobInput], progress: ProgressFn, should_cancel: CancelFn) -> list[Outcome]:
        from manifoundation.core.errors import Cancelled, ScienceError
        from manifoundation.core.pipeline import run_pipeline_batch
        from manifoundation.server.worker.convert import to_result

        outcomes: list[Outcome | None] = [None] * len(jobs)
        inputs, index, hands = [], [], []
        for i, job in enumerate(jobs):
            try:
                hand, inp = self._prepare(job)
                inputs.append(inp)
                index.append(i)
                hands.append(hand)
            except ScienceError as exc:
                outcomes[i] = error_from_exception(exc)
        reporters = [_reporter(jobs[i], progress) for i in index]

        def report(stage: str, fraction: float) -> None:
            for r in reporters:
                r(stage, fraction)

        try:
            outs = run_pipeline_batch(inputs, self.predictor, report, lambda: all(should_cancel(j.id) for j in jobs),
                                      cache=self.objects)
        except Cancelled:
            outs = [Cancelled("cancelled")] * len(inputs)
        for i, hand, out in zip(index, hands, outs, strict=True):
            job = jobs[i]
            if should_cancel(job.id) or isinstance(out, Cancelled):
                outcomes[i] = cancelled_error()
            elif isinstance(out, Exception):
                outcomes[i] = error_from_exception(out)
            else:
                outcomes[i] = to_result(out, job.request, self.model_version or "none", hand)
        missing = ErrorBody.of(ErrorType.INTERNAL_ERROR, "the pipeline gave this job no outcome")
        return [o if o is not None else missing for o in outcomes]


    def plan(self, job: PlanJob, progress: PlanProgressFn, should_cancel: CancelFn) -> PlanOutcome:
        """Plan the manipulation; planner and pipeline errors are the job's (typed: the field they name)."""
        from manifoundation.core.errors import ScienceError
        from manifoundation.core.planning import plan_manipulation
        from manifoundation.server.worker.plan_convert import to_plan_input, to_plan_result

        def report(stage: str, completed: int, total: int) -> None:
            with contextlib.suppress(ValueError):
                progress(job.id, Stage(stage), completed, total)

        try:
            hand = self._hand(job.request.robot, job.robot)
            inp = to_plan_input(job.request, hand, job.deadline)
            out = plan_manipulation(inp, self.predictor, report, lambda: should_cancel(job.id))
        except ScienceError as exc:
            return error_from_exception(exc)
        return to_plan_result(out, job.request, hand, self.model_version or "none")


def _reporter(job: JobInput, progress: ProgressFn) -> Any:
    """The pipeline's ``progress(stage, fraction)`` → the worker's per-job progress (refinement k/max)."""
    options = job.request.options
    total = max(1, options.max_iterations * options.num_proposals)
    last = [0.0]

    def report(stage: str, fraction: float) -> None:
        try:
            kind = Stage(stage)
        except ValueError:
            return
        if kind is Stage.REFINEMENT:
            done = round(fraction * total)
            iteration = min(
                options.max_iterations, done - options.max_iterations * (done // (options.max_iterations + 1))
            )
            progress(job.id, kind, fraction, max(iteration, 0), options.max_iterations)
        else:
            now = time.monotonic()
            if now - last[0] > 0.01 or fraction in (0.0, 1.0):
                last[0] = now
                progress(job.id, kind, fraction, None, None)

    return report


def _public(hand: Hand, name: str, *, builtin: bool, source: str) -> RobotPublic:
    return RobotPublic(
        name=name, builtin=builtin, dof=int(hand.dof), joint_names=list(hand.joint_names),
        lower=[float(x) for x in hand.lower], upper=[float(x) for x in hand.upper],
        fingertips=list(hand.fingertip_links), num_spheres=len(hand.sphere_radii), source=source,
    )  # fmt: skip
