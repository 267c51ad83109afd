"""`manifoundation.core.compiled.warm_up` compiles every loop for the types a request passes them: a request after it
compiles nothing more (else the first request of a worker would pay a compilation)."""

from __future__ import annotations

import numpy as np
import trimesh

from manifoundation.core.compiled import warm_up
from manifoundation.core.pipeline import SynthesisInput, TaskInput, run_pipeline
from manifoundation.core.refine import field_kernels, part_bounds, self_pairs
from manifoundation.core.robots import get_hand, kinematics_kernels

LOOPS = [
    field_kernels.disc_distances, field_kernels.winding_sum, field_kernels.within_facets, part_bounds._clearance,
    part_bounds._grid_bounds, kinematics_kernels.body_poses_one, kinematics_kernels.point_jacobian_one,
    kinematics_kernels.apply_delta_one, kinematics_kernels.on_bodies_one, self_pairs._near_pairs,
]  # fmt: skip


def test_a_request_after_the_warm_up_compiles_nothing_more():
    assert warm_up() >= 0.0
    compiled = [set(loop.signatures) for loop in LOOPS]  # other tests in this process may have added others
    assert all(compiled)
    mesh = trimesh.creation.box(extents=[0.05, 0.05, 0.08])
    pts, faces = trimesh.sample.sample_surface(mesh, 1024, seed=0)
    out = run_pipeline(SynthesisInput(
        points=np.asarray(pts), normals=np.asarray(mesh.face_normals[faces]), hand=get_hand("allegro"),
        task=TaskInput("delta_pose", translation=np.array([0.0, 0.0, 0.05])), method="random_contacts",
        max_iterations=6, seed=0,
    ))  # fmt: skip
    assert out.best is not None and out.best.quality.iterations > 0
    assert [set(loop.signatures) for loop in LOOPS] == compiled
