"""Labels from grasps that hold: the sampled grasps judged by the simulated grasp test before they label anything.

`research.data.sampling.sample_grasps` returns feasible grasps (every fingertip on the surface, no penetration, no
self-collision): a geometric criterion. With ``mani-lab data generate --physics closure`` each of them is run
through `manifoundation.core.physics.simulate_grasp` (DexGraspBench's six pushes, on the object's exact mesh) and
only those that hold become examples (issues 59 and 63: the network learns where grasps that hold touch). The test
imports nothing from the sampler or the optimiser.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from manifoundation.core.physics import ObjectShape, PhysicsResult, Protocol, from_mesh, simulate_grasp

if TYPE_CHECKING:
    import trimesh

    from manifoundation.core.robots.hand import Hand
    from research.data.sampling import Grasp

PHYSICS_MODES = ("off", "closure")
"""``off``: every feasible grasp labels; ``closure``: only those that hold in the six-push test."""


@dataclass
class HeldGrasps:
    """The grasps that held, and every verdict (in the order given)."""

    held: list[Grasp]
    results: list[PhysicsResult]


def held_grasps(
    hand: Hand, grasps: list[Grasp], mesh: trimesh.Trimesh | None = None, shape: ObjectShape | None = None,
    protocol: Protocol | None = None,
) -> HeldGrasps:  # fmt: skip
    """Judge each grasp (its contacts one per fingertip, in ``hand.fingertip_links`` order) on the object: ``shape``,
    else built once from ``mesh`` (the exact mesh the grasps were sampled on)."""
    if not grasps:
        return HeldGrasps([], [])
    if shape is None:
        if mesh is None:
            raise ValueError("held_grasps: give the object's mesh or its shape")
        shape = from_mesh(np.asarray(mesh.vertices, float), np.asarray(mesh.faces, np.int64))
    tips = list(hand.fingertip_links)
    results = [
        simulate_grasp(hand, g.palm_pos, g.palm_quat, g.q, g.contacts, g.normals, tips, shape, protocol=protocol)
        for g in grasps
    ]
    return HeldGrasps([g for g, r in zip(grasps, results, strict=True) if r.success], results)
