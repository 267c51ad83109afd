import numpy as np
import pytest

from manifoundation.core.objects import OBJECT_KINDS, make_object, object_set, radial_union


@pytest.mark.parametrize("kind", OBJECT_KINDS)
def test_every_kind_is_watertight_centred_and_sized(kind):
    obj = make_object(kind, 0.12, seed=3, num_points=256)
    assert obj.mesh.is_watertight
    assert obj.mesh.volume > 0
    np.testing.assert_allclose(obj.mesh.center_mass, 0.0, atol=1e-9)
    assert max(obj.mesh.extents) == pytest.approx(0.12)
    assert obj.points.shape == (256, 3) and obj.normals.shape == (256, 3)
    np.testing.assert_allclose(np.linalg.norm(obj.normals, axis=1), 1.0, atol=1e-9)
    # outward normals: on average they point away from the centre of mass
    assert np.mean(np.einsum("ij,ij->i", obj.points, obj.normals)) > 0


def test_seeded_and_ids_stable():
    a, b = make_object("composite", 0.1, 7), make_object("composite", 0.1, 7)
    assert a.id == b.id and a.id.startswith("composite-")
    np.testing.assert_array_equal(a.points, b.points)
    assert make_object("composite", 0.1, 8).id != a.id


def test_object_set_is_prefix_stable_and_in_range():
    small, large = object_set(4, seed=5, num_points=64), object_set(9, seed=5, num_points=64)
    assert [o.id for o in small] == [o.id for o in large[:4]]
    assert all(0.05 <= o.size <= 0.25 for o in large)
    assert {o.kind for o in large} == set(OBJECT_KINDS)


def test_composites_are_non_convex():
    assert any(not make_object("composite", 0.1, s).mesh.is_convex for s in range(4))


def test_radial_union_rejects_part_without_origin():
    import trimesh

    part = trimesh.creation.box(extents=[1, 1, 1])
    part.apply_translation([2, 0, 0])
    with pytest.raises(ValueError):
        radial_union([part])


def test_unknown_kind():
    with pytest.raises(ValueError, match="unknown object kind"):
        make_object("torus", 0.1, 0)
