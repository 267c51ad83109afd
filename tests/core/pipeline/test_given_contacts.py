"""Method "contacts" keeps the caller's contacts or says how far each moved (issue 62 #8): never more contacts than
given, a per-contact `contact_shift`, "given" only within `GIVEN_TOLERANCE`, and points far off the object refused."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from manifoundation.core.pipeline import InvalidInput, SynthesisInput, TaskInput, run_pipeline
from manifoundation.core.pipeline.prepare import MAX_GIVEN_OFFSET
from manifoundation.core.pipeline.run import GIVEN_TOLERANCE


@pytest.fixture(scope="module")
def leap_box():
    from manifoundation.core.robots import get_hand

    mesh = trimesh.creation.box((0.06, 0.06, 0.06))
    pts, faces = trimesh.sample.sample_surface_even(mesh, 1500, seed=0)
    return get_hand("leap"), mesh, np.asarray(pts), np.asarray(mesh.face_normals[faces])


def _request(leap_box, contacts: np.ndarray, **kw) -> SynthesisInput:
    hand, mesh, pts, nrm = leap_box
    return SynthesisInput(
        points=pts, normals=nrm, hand=hand, task=TaskInput("force_closure"), method="contacts", contacts=contacts,
        mesh_vertices=np.asarray(mesh.vertices), mesh_faces=np.asarray(mesh.faces), max_iterations=kw.pop("it", 30),
        **kw,
    )  # fmt: skip


@pytest.mark.parametrize("given", [
    [[0.0, -0.03, 0.0], [0.015, 0.03, 0.0], [-0.015, 0.03, 0.0]],  # three of LEAP's four fingertips
    [[0.0, -0.03, 0.0], [0.02, 0.03, 0.0], [0.0, 0.03, 0.0], [-0.02, 0.03, 0.0]],
])  # fmt: skip
def test_the_answer_has_the_given_contacts_each_with_how_far_it_moved(leap_box, given) -> None:
    given = np.array(given)
    out = run_pipeline(_request(leap_box, given, num_proposals=2))
    for p in out.proposals:
        assert p.contact_points.shape == given.shape and p.forces.shape == given.shape  # never more than given
        assert p.contact_shift is not None and p.contact_shift.shape == (len(given),)
        assert np.allclose(p.contact_shift, np.linalg.norm(p.contact_points - given, axis=1))
        moved = float(p.contact_shift.max()) > GIVEN_TOLERANCE
        assert p.contact_source == ("given_moved" if moved else "given")


def test_given_points_far_from_the_object_are_refused_naming_the_field_and_distance(leap_box) -> None:
    far = np.array([[1.0, 0.0, 0.0], [0.0, 0.03, 0.0], [0.0, -0.03, 0.0]])
    with pytest.raises(InvalidInput, match=r"contacts\.points: point 0 lies 0\.97\d* m from the object's surface") as e:
        run_pipeline(_request(leap_box, far))
    assert f"{MAX_GIVEN_OFFSET}" in str(e.value)
