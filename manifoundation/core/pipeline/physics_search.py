"""``options.simulate`` inside the pipeline: every proposal judged by the simulated grasp test as it is made, and
more candidates drawn until enough of them hold.

The geometric checks cannot tell which of several verified proposals holds in physics (on 43 third-party objects
the pipeline's first of four held for LEAP in 9, the best of the four by the test in 24;
research/results/physics.md). So with ``simulate`` the pipeline draws `SynthesisInput.candidates` starts (network
samples and opposed contact sets; at least 16), refines and judges them one after another, stops as soon as
``num_proposals`` of them are verified and held, and returns the ``num_proposals`` best in `physics_order`
(verified and held, held, verified). The test (`manifoundation.core.physics`) is the one `mani-lab eval physics`
runs: force closure's six pushes, or for a ``delta_pose`` task the executed motion; on the sent mesh, else on the
points and their normals.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from manifoundation.core.physics import (
    ObjectShape,
    PhysicsResult,
    Protocol,
    SceneCache,
    from_mesh,
    from_points,
    physics_order,
    simulate_grasp,
    simulate_motion,
)

if TYPE_CHECKING:
    from manifoundation.core.pipeline.prepare import Prepared
    from manifoundation.core.pipeline.types import ProposalOutput


class PhysicsJudge:
    """The simulated test for one request's proposals; the object is built once, at the first proposal, and its
    scene compiled once for every grasp tested (`SceneCache`)."""

    def __init__(self, prep: Prepared) -> None:
        self.prep = prep
        self._shape: ObjectShape | None = None
        self._scenes: SceneCache | None = None

    def shape(self) -> ObjectShape:
        """The object the test builds: the sent mesh, else patches from the points and their normals."""
        if self._shape is None:
            inp = self.prep.inp
            if inp.mesh_vertices is not None and inp.mesh_faces is not None:
                self._shape = from_mesh(np.asarray(inp.mesh_vertices, float), np.asarray(inp.mesh_faces, np.int64))
            else:
                self._shape = from_points(self.prep.cloud.points, self.prep.cloud.normals)
        return self._shape

    def __call__(self, p: ProposalOutput, complete: bool = False) -> PhysicsResult | None:
        """The test's result for ``p`` (None: a proposal without a hand pose). Searching (``complete=False``) the
        pushes stop at the first that moves the object (the verdict is the same; a failing candidate costs about
        half); `complete_trials` re-runs the ones returned so their answer lists every push."""
        if p.palm_position is None or p.palm_quaternion is None or p.joint_values is None or not p.fingertips:
            return None
        inp = self.prep.inp
        grasp = (inp.hand, p.palm_position, p.palm_quaternion, p.joint_values, p.contact_points, p.contact_normals,
                 p.fingertips, self.shape())  # fmt: skip
        task = inp.task
        if task.kind == "delta_pose":
            translation = np.zeros(3) if task.translation is None else np.asarray(task.translation, float)
            rotation = np.array([1.0, 0, 0, 0]) if task.rotation is None else np.asarray(task.rotation, float)
            return simulate_motion(*grasp, translation, rotation)
        if self._scenes is None:  # the object's scene compiled once, re-posed for each grasp
            self._scenes = SceneCache(self.shape())
        return simulate_grasp(*grasp, protocol=Protocol(stop_at_first_failure=not complete), scenes=self._scenes)

    def complete_trials(self, proposals: list[ProposalOutput]) -> None:
        """Every push of each returned proposal whose search stopped at its first failing one."""
        for p in proposals:
            if p.physics is not None and p.physics.test == "closure" and p.physics.reason == "moved":
                p.physics = self(p, complete=True)


def enough_held(proposals: list[ProposalOutput], wanted: int) -> bool:
    """Whether ``wanted`` of the judged proposals are verified and held (what the answer calls a success)."""
    return sum(p.quality.success and p.physics is not None and p.physics.success for p in proposals) >= wanted


def best_by_physics(proposals: list[ProposalOutput], wanted: int) -> list[ProposalOutput]:
    """The ``wanted`` best of the judged proposals (`physics_order`; ties keep the geometric rank given)."""
    order = physics_order([bool(p.quality.success) for p in proposals],
                          [p.physics is not None and p.physics.success for p in proposals])  # fmt: skip
    return [proposals[i] for i in order[:wanted]]
