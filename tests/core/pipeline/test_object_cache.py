import numpy as np
import pytest
import trimesh

from manifoundation.core.pipeline import InvalidInput, SynthesisInput, TaskInput, run_pipeline
from manifoundation.core.pipeline.object_cache import BYTES_PER_FACE, LeastRecentlyUsed, ObjectCache, digest
from manifoundation.core.pipeline.prepare import prepare


@pytest.fixture(scope="module")
def box():
    mesh = trimesh.creation.box(extents=[0.04, 0.06, 0.06])
    pts, faces = trimesh.sample.sample_surface(mesh, 512, seed=0)
    return np.asarray(pts), np.asarray(mesh.face_normals[faces]), mesh


@pytest.fixture(scope="module")
def gripper():
    from manifoundation.core.robots import get_hand

    return get_hand("panda_gripper")


def _inp(box, gripper, **kw):
    pts, nrm, mesh = box
    base = dict(points=pts, normals=nrm, hand=gripper, task=TaskInput("force_closure"), method="random_contacts",
                mesh_vertices=np.asarray(mesh.vertices), mesh_faces=np.asarray(mesh.faces), seed=3)
    base.update(kw)
    return SynthesisInput(**base)


def test_digest_tells_apart_bytes_dtypes_shapes_and_absence():
    a = np.arange(6, dtype=np.float64).reshape(2, 3)
    assert digest(a) == digest(a.copy()) == digest(np.asfortranarray(a))
    assert digest(a) != digest(a.reshape(3, 2))
    assert digest(a) != digest(a.astype(np.float32))
    b = a.copy()
    b[1, 2] += 1e-12
    assert digest(a) != digest(b)
    assert digest(a, None) != digest(a, np.zeros((0, 3)))
    assert digest(a, None) != digest(None, a)


def test_least_recently_used_keeps_the_last_used_and_builds_once():
    lru: LeastRecentlyUsed[int] = LeastRecentlyUsed(2)
    built = []

    def build(v):
        return lambda: built.append(v) or v

    assert lru.get(b"a", build(1)) == 1 and lru.get(b"b", build(2)) == 2
    assert lru.get(b"a", build(99)) == 1  # kept: not rebuilt, and now the most recent
    lru.get(b"c", build(3))  # evicts b, the least recently used
    assert len(lru) == 2 and lru.get(b"b", build(4)) == 4 and lru.get(b"a", build(5)) == 5
    assert built == [1, 2, 3, 4, 5]


def test_least_recently_used_keeps_within_its_bytes_and_never_keeps_an_oversized_value():
    lru: LeastRecentlyUsed[int] = LeastRecentlyUsed(10, max_bytes=100, size=lambda v: v)
    for key, value in ((b"a", 40), (b"b", 40), (b"c", 40)):  # c pushes the total to 120: a goes
        lru.get(key, lambda value=value: value)
    assert len(lru) == 2 and lru.bytes == 80
    assert lru.get(b"big", lambda: 101) == 101  # returned, not kept: nothing else evicted for it
    assert len(lru) == 2 and lru.bytes == 80 and lru.get(b"big", lambda: 7) == 7


def test_an_object_beyond_the_byte_bound_is_used_but_not_kept(box, gripper):
    cache = ObjectCache(max_bytes=BYTES_PER_FACE * len(box[2].faces) - 1)  # not even the mesh fits
    first = prepare(_inp(box, gripper), cache)
    again = prepare(_inp(box, gripper), cache)
    assert first.mesh is not again.mesh and first.cloud is not again.cloud
    assert len(cache.meshes) == len(cache.objects) == 0 and cache.meshes.bytes == cache.objects.bytes == 0
    assert again.mass == first.mass


def test_the_same_object_is_prepared_once_and_answers_as_a_fresh_build(box, gripper):
    cache = ObjectCache()
    first = prepare(_inp(box, gripper), cache)
    again = prepare(_inp(box, gripper, task=TaskInput("delta_pose", translation=np.array([0.0, 0.0, 0.03]))), cache)
    assert again.cloud is first.cloud and again.mesh is first.mesh  # shared, not rebuilt
    assert cache.objects.hits == 1 and cache.meshes.hits == 1

    other_points = prepare(_inp(box, gripper, points=box[0][::-1].copy(), normals=box[1][::-1].copy()), cache)
    assert other_points.cloud is not first.cloud and other_points.mesh is first.mesh  # the mesh's structures shared

    kept = run_pipeline(_inp(box, gripper), cache=cache)
    fresh = run_pipeline(_inp(box, gripper), cache=ObjectCache(enabled=False))
    for a, b in zip(kept.proposals, fresh.proposals, strict=True):
        assert a.quality.success == b.quality.success
        np.testing.assert_array_equal(a.joint_values, b.joint_values)
        np.testing.assert_array_equal(a.palm_position, b.palm_position)
        np.testing.assert_array_equal(a.contact_points, b.contact_points)


def test_a_cached_object_does_not_follow_the_callers_array(box, gripper):
    cache = ObjectCache()
    pts = box[0].copy()
    first = prepare(_inp(box, gripper, points=pts), cache)
    before = first.cloud.points.copy()
    pts += 1.0  # the caller reuses its buffer for another object
    np.testing.assert_array_equal(first.cloud.points, before)
    moved = prepare(_inp(box, gripper, points=pts), cache)
    assert moved.cloud is not first.cloud and np.allclose(moved.cloud.points, before + 1.0)


def test_density_is_not_part_of_the_object_but_changes_the_mass(box, gripper):
    cache = ObjectCache()
    light = prepare(_inp(box, gripper, properties={"density": 100.0}), cache)
    heavy = prepare(_inp(box, gripper, properties={"density": 1000.0}), cache)
    assert heavy.cloud is light.cloud
    assert heavy.mass == pytest.approx(10 * light.mass)


def test_a_bad_object_is_refused_and_not_kept(box, gripper):
    cache = ObjectCache()
    flat = np.c_[np.random.default_rng(0).uniform(size=(64, 2)), np.zeros(64)]
    bad_normals = np.zeros((64, 3))
    with pytest.raises(InvalidInput):
        prepare(_inp(box, gripper, points=flat, normals=bad_normals, mesh_vertices=None, mesh_faces=None), cache)
    assert len(cache.objects) == 0
