"""A deformable answer judged in the simulator: `options.simulate_rollout`.

The object is rebuilt as a simulation body from its points (`models.deformable.reconstruct`), each proposal's
contacts are grasped and moved by their motions (`models.deformable.simulate`, the same physics as the data and
the evaluation), and the rollout is scored against the target (the points plus the per-point target motion; for
unordered targets, the registered motion) by the paper's shape metric (`models.deformable.metrics`). The body is
rebuilt once per request and shared by the proposals.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from models.pipeline.types import ProposalOutput


def judge_by_rollout(
    material: str, points: np.ndarray, normals: np.ndarray, motion: np.ndarray, properties: dict[str, float],
    proposals: list[ProposalOutput],
) -> list[ProposalOutput]:
    """Each proposal with its rollout, shape error and the metric's verdict as its quality.

    Args:
        material: cloth, rope or plasticine.
        points: (N, 3) the object's points; normals: (N, 3) their outward normals.
        motion: (N, 3) the target motion of every point (target = points + motion).
        properties: the material's properties.
        proposals: answers with ``contact_motions``.

    Raises:
        InvalidInput: the points cannot be rebuilt as that material's body (naming ``object.points``).
    """
    from models.deformable.materials import with_defaults
    from models.deformable.metrics import shape_score
    from models.deformable.reconstruct import body_from_cloud
    from models.deformable.simulate import simulate

    rebuilt = body_from_cloud(material, points, normals, with_defaults(material, properties))
    target = points + motion
    judged = []
    for p in proposals:
        assert p.contact_motions is not None
        run = simulate(rebuilt.body, rebuilt.to_simulator(p.contact_points), p.contact_motions)
        rollout = rebuilt.cloud(run.vertices)
        score = shape_score(material, points, target, rollout)
        failures = [] if score.success else ["rollout_target"]
        if not run.stable:
            failures.append("rollout_unstable")
        quality = replace(p.quality, success=score.success and run.stable, converged=run.stable,
                          reason="rollout_reached_target" if score.success else "rollout_missed_target",
                          failures=failures)  # fmt: skip
        judged.append(replace(p, quality=quality, rollout_points=rollout, shape_error=score.top_mean_error))
    return sorted(judged, key=lambda q: (not q.quality.success, q.shape_error or 0.0))
