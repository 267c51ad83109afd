"""Wire ↔ science: `SynthesisRequest` → `manifoundation.core.pipeline.SynthesisInput`, `SynthesisOutput` →
`SynthesisResult`.


Imported in the worker process only (it imports `models`, hence torch).
"""

from __future__ import annotations

import time
from typing import TYPE_CHECKING

import numpy as np

from manifoundation.contract import (
    HandMesh,
    IterationRecord,
    Method,
    PhysicsMotion,
    PhysicsQuality,
    PhysicsTrial,
    Proposal,
    Quality,
    SynthesisRequest,
    SynthesisResult,
)
from manifoundation.core.pipeline import (
    JointInput,
    ProposalOutput,
    SynthesisInput,
    SynthesisOutput,
    TaskInput,
    physics_mode,
)

if TYPE_CHECKING:
    from manifoundation.core.physics import PhysicsResult
    from manifoundation.core.robots.hand import Hand

_BIG = float(np.finfo(np.float64).max)


def method_of(request: SynthesisRequest) -> str:
    """The pipeline method: "auto" is the given contacts when present, else the network."""
    if request.options.method is Method.AUTO:
        return "contacts" if request.contacts is not None else "network"
    return request.options.method.value


def to_input(request: SynthesisRequest, hand: Hand, deadline: float | None = None) -> SynthesisInput:
    """The core input of ``request`` for ``hand`` (a `manifoundation.core.robots.Hand`).

    Args:
        deadline: unix time after which refinement stops (converted to a `time.monotonic()` value).
    """
    obj, task, options = request.object, request.task, request.options
    joint = None
    if obj.joint is not None:
        joint = JointInput(obj.joint.type, obj.joint.axis, obj.joint.origin, obj.joint.part_mask.astype(bool))
    core_task = TaskInput(
        kind=task.kind,
        translation=getattr(task, "translation", None),
        rotation=getattr(task, "rotation", None),
        motion=getattr(task, "motion", None),
        targets=getattr(task, "targets", None),
        wrench=getattr(task, "wrench", None),
        delta=getattr(task, "delta", None),
        correspondence=getattr(task, "correspondence", "index"),
    )
    return SynthesisInput(
        points=obj.points.astype(np.float64),
        hand=hand,
        task=core_task,
        normals=None if obj.normals is None else obj.normals.astype(np.float64),
        material=obj.material.value,
        properties=obj.properties.present(),
        mask=None if obj.region_mask is None else obj.region_mask.astype(bool),
        joint=joint,
        mesh_vertices=None if obj.mesh is None else obj.mesh.vertices,
        mesh_faces=None if obj.mesh is None else obj.mesh.faces,
        contacts=None if request.contacts is None else request.contacts.points.astype(np.float64),
        method=method_of(request),
        num_proposals=options.num_proposals,
        refine=options.refine,
        max_iterations=options.max_iterations,
        seed=options.seed,
        deadline=None if deadline is None else time.monotonic() + (deadline - time.time()),
        return_history=options.return_history,
        simulate_rollout=options.simulate_rollout,
        handless=request.robot is None,
        num_contacts=options.num_contacts,
        hand_key=hand.name,
        stop_after_verified=options.stop_after_verified,
        rollout_corrections=options.rollout_corrections,
        simulate=physics_mode(options.simulate) if obj.material.value == "rigid" and request.robot is not None
        else "off",
    )


def _finite(value: float) -> float:
    return float(value) if np.isfinite(value) else _BIG


def physics_quality(r: PhysicsResult) -> PhysicsQuality:
    """The wire form of a proposal's simulated grasp test (the pipeline ran it: ``simulate``)."""
    m = r.motion
    return PhysicsQuality(
        held=r.success, reason=r.reason, test="motion" if r.test == "motion" else "closure",
        penetration=_finite(r.penetration),
        trials=[PhysicsTrial(direction=t.direction, translation=_finite(t.translation),
                             rotation=_finite(t.rotation), held=t.held) for t in r.trials],
        motion=None if m is None else PhysicsMotion(
            translation_error=_finite(m.translation_error), rotation_error=_finite(m.rotation_error),
            dropped=m.dropped, reached=m.reached),
        tip_gaps=[_finite(g) for g in r.tip_gaps], touching_after_squeeze=r.contacts_after_squeeze,
        pregrasp=[float(v) for v in r.pregrasp], squeeze=[float(v) for v in r.squeeze], seconds=r.seconds,
        object_pieces=r.object_pieces,
    )  # fmt: skip


def to_proposal(
    p: ProposalOutput, hand: Hand | None = None, *, history: bool = False, mesh: bool = False,
    physics: PhysicsQuality | None = None,
) -> Proposal:  # fmt: skip
    """The wire proposal of one of the pipeline's proposals (a single request's, or a plan step's).

    Args:
        hand: when given, the hand's collision spheres at the proposal's pose (and with ``mesh``, its posed
            collision meshes) travel with it, for viewers.
        history: include the refinement's per-iteration record.
        physics: the simulated grasp test's figures (`physics_quality`): success then also requires that it held.
    """
    q = p.quality
    failures = list(q.failures)
    if physics is not None and not physics.held:
        failures.append("physics")
    quality = Quality(
        success=bool(q.success) and (physics is None or physics.held), converged=bool(q.converged), reason=q.reason,
        iterations=int(q.iterations), wrench_residual=_finite(q.wrench_residual),
        max_tip_distance=_finite(q.max_tip_distance), penetration_depth=_finite(q.penetration_depth),
        self_collision_depth=_finite(q.self_collision_depth),
        epsilon=None if q.epsilon is None or not np.isfinite(q.epsilon) else float(q.epsilon),
        failures=failures, geometry=q.geometry, physics=physics,
    )  # fmt: skip
    records = None
    if history and p.history is not None:
        records = [IterationRecord(residual=_finite(h.residual), tip_distance=_finite(h.tip_distance),
                                   step=_finite(h.step)) for h in p.history]  # fmt: skip
    posed = None if p.palm_position is None else p.pose()  # no hand pose: a hand-free deformable's answer
    spheres = posed_mesh = None
    if hand is not None and posed is not None:
        from manifoundation.core.robots.view import posed_mesh as posed_hand_mesh
        from manifoundation.core.robots.view import posed_spheres

        spheres = posed_spheres(hand, posed.palm_pos, posed.palm_quat, posed.q)
        if mesh:
            vertices, faces = posed_hand_mesh(hand, posed.palm_pos, posed.palm_quat, posed.q)
            posed_mesh = HandMesh(vertices=vertices, faces=faces)
    return Proposal(
        contact_points=np.asarray(p.contact_points, dtype=np.float64).reshape(-1, 3),
        contact_normals=np.asarray(p.contact_normals, dtype=np.float64).reshape(-1, 3),
        forces=np.asarray(p.forces, dtype=np.float64).reshape(-1, 3),
        fingertips=list(p.fingertips),
        palm_position=None if posed is None else posed.palm_pos.astype(np.float64),
        palm_quaternion=None if posed is None else posed.palm_quat.astype(np.float64),
        joint_names=list(p.joint_names),
        joint_values=np.zeros(0) if posed is None else posed.q.astype(np.float64),
        quality=quality,
        contact_source=p.contact_source,
        hand_spheres=spheres,
        hand_mesh=posed_mesh,
        history=records,
        contact_motions=None if p.contact_motions is None else np.asarray(p.contact_motions, np.float64),
        network_sample=p.network_sample,
        network_forces=None if p.network_forces is None else np.asarray(p.network_forces, np.float64),
        rollout_points=None if p.rollout_points is None else np.asarray(p.rollout_points, np.float64),
        shape_error=None if p.shape_error is None else _finite(p.shape_error),
        contact_shift=None if p.contact_shift is None else np.asarray(p.contact_shift, np.float64),
    )


def to_result(
    output: SynthesisOutput, request: SynthesisRequest, model_version: str, hand: Hand | None = None
) -> SynthesisResult:
    """The wire result of ``output`` (maps and history only when the request asked for them).

    With ``hand``, each proposal carries the hand's collision spheres at its pose; for a rigid object and a robot
    the pipeline judged the proposals by the simulated grasp test unless ``options.simulate`` is false (`physics_mode`;
    with true it searched until enough held) and ordered them by it
    (`manifoundation.core.pipeline.physics_search`): ``quality.physics`` carries it and
    ``quality.success`` requires that it held (the ``heatmap`` stays the one of the pipeline's first proposal —
    ``network_sample`` says which sample each came from).
    """
    options = request.options
    proposals = [
        to_proposal(p, hand, history=options.return_history, mesh=options.return_hand_mesh,
                    physics=None if p.physics is None else physics_quality(p.physics))
        for p in output.proposals
    ]  # fmt: skip
    return SynthesisResult(
        hand=output.hand,
        model_version=model_version,
        proposals=proposals,
        heatmap=output.heatmap if options.return_heatmap and output.heatmap is not None else None,
        heatmaps=output.heatmaps if options.return_all_heatmaps and output.heatmaps is not None else None,
        force_map=output.force_map if options.return_force_map and output.force_map is not None else None,
        timings={k: float(v) for k, v in output.timings.items()},
    )
