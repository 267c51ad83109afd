"""`verify` with ``complete=False`` (the refinement's stop question): the same verdict, the contact tests' failures,
no collision tests once those fail; and the pipeline's per-request verifier completes such an answer."""

import numpy as np

from manifoundation.core.refine.state import HandPose
from manifoundation.core.refine.verify import verify

CONTACT_TESTS = {"wrench_residual", "tip_distance"}


def _poses(start: HandPose) -> list[HandPose]:
    inward = -start.palm_pos / np.linalg.norm(start.palm_pos)
    return [start, HandPose(start.palm_pos + 0.04 * inward, start.palm_quat, start.q),
            HandPose(start.palm_pos - 0.03 * inward, start.palm_quat, start.q)]  # fmt: skip


def test_an_incomplete_verification_gives_the_same_verdict_and_stops_at_the_contact_tests(leap_on_a_box):
    hand, mesh, field, task, start = leap_on_a_box
    stopped = 0
    for pose in _poses(start):
        for geometry in (mesh, None):
            full = verify(hand, pose, field, task, 0.8, geometry)
            quick = verify(hand, pose, field, task, 0.8, geometry, complete=False)
            assert quick.success == full.success and full.complete
            early = [f for f in full.failures if f in CONTACT_TESTS]
            if early:  # stopped there: the collision tests not run
                stopped += 1
                assert quick.failures == early and not quick.complete
                assert np.isnan(quick.penetration) and np.isnan(quick.self_collision)
            else:  # nothing to stop at: every test, as the full one
                assert quick.complete and quick.failures == full.failures
                assert quick.penetration == full.penetration
            assert quick.max_tip_distance == full.max_tip_distance
            assert quick.residual_norm == full.residual_norm
    assert stopped >= 2  # the fixture's poses do fail a contact test


def test_the_requests_verifier_completes_an_incomplete_answer(leap_on_a_box):
    from manifoundation.core.pipeline import SynthesisInput, TaskInput
    from manifoundation.core.pipeline.prepare import prepare
    from manifoundation.core.pipeline.run import _Verifier

    hand, mesh, field, _, start = leap_on_a_box
    inp = SynthesisInput(points=field.points, normals=field.normals, hand=hand, method="random_contacts",
                         task=TaskInput("delta_pose", translation=np.array([0.0, 0.0, 0.05])),
                         mesh_vertices=np.asarray(mesh.vertices), mesh_faces=np.asarray(mesh.faces))  # fmt: skip
    verified = _Verifier(prepare(inp))
    far = _poses(start)[2]
    quick = verified(far, complete=False)
    assert not quick.success and not quick.complete
    assert verified(far, complete=False) is quick  # asked again: the same answer, not measured twice
    full = verified(far)
    assert full.complete and not np.isnan(full.penetration) and full.success == quick.success
    assert verified(far, complete=False) is full  # a complete answer serves both questions
