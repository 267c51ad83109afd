"""Deformable requests (cloth, rope, plasticine with a ``point_motion`` or ``target_points`` task) in the pipeline.

No wrench and no refinement: the answer is contacts with a post-contact motion each
(`manifoundation.core.deformable.answer`). Methods: "network" (the heatmap's NMS contacts with the task's motion at
them), "random_contacts" (spread points with the task's motion at them), "contacts" (the given points, with the task's
motion at them). With a hand, each proposal names the fingertip at each contact from the rigid fit of the hand's
fingertips onto the contacts (`manifoundation.core.refine.initialise`, the pose is that fit's, not refined);
``quality.success`` is False with reason ``deformable_open_loop`` unless the request asks for ``simulate_rollout``: then
each answer is applied in the simulator and judged by the shape metric
(`manifoundation.core.pipeline.deformable_rollout`), and when every proposal has the network's own contacts, the
most-moved points (`manifoundation.core.deformable.answer.moving_indices`, ``motion_fallback``) are simulated beside
them as one more candidate; the best ``num_proposals`` by the rollout are returned. Unordered targets (``target_points``
with ``correspondence="unknown"``) get their per-point motion by coherent point drift and optimal transport
(`manifoundation.core.deformable.registration`).
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from manifoundation.core.pipeline.types import (
    InvalidInput,
    ProposalOutput,
    QualityOutput,
    SynthesisInput,
    SynthesisOutput,
)

if TYPE_CHECKING:
    from manifoundation.core.deformable.answer import DeformableContacts
    from manifoundation.core.network.inference import NetworkInput, NetworkOutput

DEFORMABLE_MATERIALS = ("cloth", "rope", "plasticine")
DEFORMABLE_TASKS = ("point_motion", "target_points")
DEFORMABLE_METHODS = ("network", "random_contacts", "contacts")
HANDLESS_CONTACTS = 2  # contacts per proposal without a robot, unless the request says (two grasp points)
DEFORMABLE_HAND = "panda_gripper"
"""The hand the network sees for a deformable request without a robot: the hand of its training data."""


@dataclass
class PreparedDeformable:
    """A validated deformable request: its cloud (points, normals, mask) and the per-point target motion."""

    inp: SynthesisInput
    points: np.ndarray
    normals: np.ndarray
    mask: np.ndarray | None
    motion: np.ndarray
    seconds: float


def is_deformable_task(inp: SynthesisInput) -> bool:
    """A deformable material with a per-point task (other tasks on deformables are fitted rigidly)."""
    return inp.material in DEFORMABLE_MATERIALS and inp.task.kind in DEFORMABLE_TASKS


def prepare_deformable(inp: SynthesisInput) -> PreparedDeformable:
    """Check the arrays and derive the per-point motion (registration for unordered targets)."""
    from manifoundation.core.geometry.object import estimate_normals
    from manifoundation.core.pipeline.prepare import _array

    t0 = time.perf_counter()
    points = _array("points", inp.points, (None, 3))
    n = len(points)
    if inp.method not in DEFORMABLE_METHODS:
        raise InvalidInput(f"method: {inp.method!r} is for rigid objects; a deformable takes "
                           f"{', '.join(DEFORMABLE_METHODS)}")  # fmt: skip
    if inp.normals is not None:
        normals = _array("normals", inp.normals, (n, 3))
    else:
        from scipy.spatial import cKDTree

        normals = estimate_normals(points, cKDTree(points))
    mask = None if inp.mask is None else np.asarray(inp.mask, dtype=bool).reshape(-1)
    if mask is not None and (mask.shape != (n,) or not mask.any()):
        raise InvalidInput(f"mask: expected ({n},) with at least one allowed point")
    task = inp.task
    if task.kind == "point_motion":
        motion = _array("task.motion", task.motion, (n, 3))
    elif getattr(task, "correspondence", "index") == "unknown":
        from manifoundation.core.deformable.registration import transport_motion

        targets = _array("task.targets", task.targets, (None, 3))
        motion = transport_motion(points, targets)
    else:
        motion = _array("task.targets", task.targets, (n, 3)) - points
    if inp.method == "contacts" and inp.contacts is None:
        raise InvalidInput("contacts: required with method 'contacts'")
    return PreparedDeformable(inp, points, normals, mask, motion, time.perf_counter() - t0)


def network_input(p: PreparedDeformable) -> NetworkInput:
    """The `manifoundation.core.network.inference.NetworkInput` of a deformable request: its properties completed with
    the
    material's defaults, as the simulator completes them (the training data carry every one)."""
    from manifoundation.core.deformable.materials import with_defaults
    from manifoundation.core.network.inference import NetworkInput

    hand = p.inp.hand
    properties = with_defaults(p.inp.material, dict(p.inp.properties))
    return NetworkInput(
        points=p.points, normals=p.normals, motion=p.motion,
        mask=p.mask if p.mask is not None else np.ones(len(p.points), dtype=bool),
        properties={k: v for k, v in properties.items() if k != "yield_stress"},
        hand_points=np.asarray(hand.surface_points), hand_normals=np.asarray(hand.surface_normals),
        hand_key=str(p.inp.hand_key or getattr(hand, "name", "hand")),
    )  # fmt: skip


def finish_deformable(p: PreparedDeformable, net_out: NetworkOutput | None, timings: dict[str, float]
                      ) -> SynthesisOutput:  # fmt: skip
    """Proposals of contacts + post-contact motions (see the module doc)."""
    from manifoundation.core.deformable.answer import (
        DeformableContacts,
        deformable_contacts,
        moving_indices,
        spread_indices,
    )
    from manifoundation.core.refine.field import PointCloudField
    from manifoundation.core.refine.initialise import initialise

    inp, hand = p.inp, p.inp.hand
    t0 = time.perf_counter()
    m = (inp.num_contacts or HANDLESS_CONTACTS) if inp.handless else int(hand.num_fingertips)
    rng = np.random.default_rng(inp.seed)
    allowed = np.flatnonzero(p.mask) if p.mask is not None else np.arange(len(p.points))
    sets: list[DeformableContacts] = []
    for k in range(inp.num_proposals):
        if inp.method == "network" and net_out is not None:
            explore = rng if k > 0 else None  # the first proposal's fallback takes the most-moved point
            sets.append(deformable_contacts(p.points, net_out.heatmaps[k], p.motion, p.mask, m, explore))
        elif inp.method == "contacts":
            given = np.asarray(inp.contacts, dtype=np.float64).reshape(-1, 3)[:m]
            idx = PointCloudField(p.points, p.normals).nearest_index(given)
            sets.append(DeformableContacts(idx, p.points[idx], p.motion[idx], "given"))
        else:
            idx = spread_indices(p.points, allowed, m, rng)
            sets.append(DeformableContacts(idx, p.points[idx], p.motion[idx], "random"))
    if inp.simulate_rollout and inp.method == "network" and all(s.source == "network" for s in sets):
        # judged in the simulator: the most-moved points compete with the network's contacts for a place
        idx = moving_indices(p.points, allowed, p.motion, m)
        sets.append(DeformableContacts(idx, p.points[idx], p.motion[idx], "motion_fallback"))
    cloud = PointCloudField(p.points, p.normals, p.mask)
    proposals = []
    for s in sets:
        if inp.handless:
            proposals.append(_contacts_only(s, p.normals))
            continue
        cand = initialise(hand, cloud, s.points, p.normals[s.indices])[0]
        tips = [hand.fingertip_links[j] for j in cand.assignment]
        quality = _open_loop(tip_distance=float(cand.rms))
        proposals.append(ProposalOutput(
            contact_points=s.points, contact_normals=p.normals[s.indices], forces=np.zeros_like(s.points),
            fingertips=tips, palm_position=cand.pose.palm_pos.copy(), palm_quaternion=cand.pose.palm_quat.copy(),
            joint_names=list(hand.joint_names), joint_values=cand.pose.q.copy(), quality=quality,
            contact_source=s.source, contact_motions=s.motions,
        ))  # fmt: skip
    timings["initialisation"] = time.perf_counter() - t0
    if inp.simulate_rollout:
        from manifoundation.core.pipeline.deformable_rollout import judge_by_rollout

        t0 = time.perf_counter()
        proposals = judge_by_rollout(inp.material, p.points, p.normals, p.motion, inp.properties, proposals,
                                     inp.rollout_corrections)  # fmt: skip
        proposals = proposals[: inp.num_proposals]  # the best by the rollout (a competing candidate may drop)
        timings["rollout"] = time.perf_counter() - t0
    heat = force = None
    if net_out is not None:
        heat = np.asarray(net_out.heatmaps[0], dtype=np.float64)
        force = np.asarray(net_out.force_maps[0], dtype=np.float64)
    name = None if inp.handless else str(getattr(hand, "name", "hand"))
    every = None if net_out is None else np.asarray(net_out.heatmaps, dtype=np.float64)
    return SynthesisOutput(hand=name, proposals=proposals, heatmap=heat, force_map=force, heatmaps=every,
                           timings=timings)  # fmt: skip


def _open_loop(tip_distance: float) -> QualityOutput:
    """The quality of an answer nobody simulated (``tip_distance``: the fingertips' fit, m; 0 without a hand)."""
    return QualityOutput(success=False, converged=False, reason="deformable_open_loop", iterations=0,
                         wrench_residual=0.0, max_tip_distance=tip_distance, penetration_depth=0.0,
                         self_collision_depth=0.0, epsilon=None, failures=["not_simulated"])  # fmt: skip


def _contacts_only(s: DeformableContacts, normals: np.ndarray) -> ProposalOutput:
    """A proposal without a robot: the contacts and their motions, for whatever gripper takes them."""
    return ProposalOutput(
        contact_points=s.points, contact_normals=normals[s.indices], forces=np.zeros_like(s.points), fingertips=[],
        palm_position=None, palm_quaternion=None, joint_names=[], joint_values=None, quality=_open_loop(0.0),
        contact_source=s.source, contact_motions=s.motions,
    )  # fmt: skip
