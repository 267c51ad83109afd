"""Bodies rebuilt from their clouds move like the generators' own meshes under the same manipulation."""

from __future__ import annotations

import numpy as np
import pytest

from manifoundation.core.deformable.metrics import shape_score
from manifoundation.core.deformable.procedures import random_manipulation
from manifoundation.core.deformable.reconstruct import body_from_cloud
from manifoundation.core.deformable.shapes import make_body
from manifoundation.core.deformable.simulate import SimConfig, simulate
from manifoundation.core.errors import InvalidInput

QUICK = SimConfig(move_seconds=0.6, settle_seconds=0.2)


@pytest.mark.parametrize(("material", "kind", "seed"), [("cloth", "square", 1), ("rope", "rope", 3)])
def test_rebuilt_cloth_and_rope_reach_the_native_rollout(material: str, kind: str, seed: int) -> None:
    body = make_body(material, kind, seed)
    manipulation = random_manipulation(body, np.random.default_rng(seed))
    native = simulate(body, manipulation.contacts, manipulation.motions, QUICK)
    rebuilt = body_from_cloud(material, body.points, body.normals, body.properties)
    contacts = rebuilt.to_simulator(body.points[manipulation.contacts])
    rollout = rebuilt.cloud(simulate(rebuilt.body, contacts, manipulation.motions, QUICK).vertices)
    score = shape_score(material, body.points, native.cloud, rollout)
    assert score.success, score
    assert score.top_mean_error < 0.1 * shape_score(material, body.points, native.cloud, body.points).top_mean_error


@pytest.mark.slow
def test_rebuilt_plasticine_embeds_the_cloud_exactly_and_presses_like_the_native_box() -> None:
    body = make_body("plasticine", "box", 7)
    rebuilt = body_from_cloud("plasticine", body.points, body.normals, body.properties)
    np.testing.assert_allclose(rebuilt.cloud(rebuilt.body.vertices), body.points, atol=1e-12)
    assert rebuilt.body.vertices[:, 2].min() == pytest.approx(1e-3)  # resting on the simulator's table
    np.testing.assert_allclose(rebuilt.body.vertices, body.vertices, atol=1e-12)  # the generator's lattice body
    press = random_manipulation(body, np.random.default_rng(7))
    native = simulate(body, press.contacts, press.motions, QUICK).cloud
    rollout = rebuilt.cloud(simulate(rebuilt.body, rebuilt.to_simulator(body.points[press.contacts]),
                                     press.motions, QUICK).vertices)  # fmt: skip
    assert shape_score("plasticine", body.points, native, rollout).success  # the 3D rule (closure, top points)
    assert np.abs(rollout - native).max() < 1e-4


def test_a_plasticine_cloud_off_any_lattice_is_filled_with_a_lattice_of_its_own() -> None:
    body = make_body("plasticine", "sphere", 2)
    jittered = body.points + np.random.default_rng(0).normal(scale=2e-4, size=body.points.shape)
    rebuilt = body_from_cloud("plasticine", jittered, body.normals, body.properties)
    np.testing.assert_allclose(rebuilt.cloud(rebuilt.body.vertices), jittered, atol=1e-9)  # embedded, carried
    lo, hi = jittered.min(axis=0), jittered.max(axis=0)
    inside = rebuilt.body.vertices - rebuilt.offset
    assert np.all(inside >= lo - 0.1 * (hi - lo)) and np.all(inside <= hi + 0.1 * (hi - lo))


def test_clouds_that_are_no_such_body_are_refused_naming_the_points() -> None:
    rng = np.random.default_rng(0)
    blob = rng.normal(size=(200, 3)) * 0.05
    normals = blob / np.linalg.norm(blob, axis=1, keepdims=True)
    with pytest.raises(InvalidInput, match=r"object\.points: a cloth rollout needs the cloth lying flat"):
        body_from_cloud("cloth", blob, normals, {})
    pieces = np.concatenate([blob[:100] * 0.1, blob[100:] * 0.1 + [1.0, 0.0, 0.0]])
    with pytest.raises(InvalidInput, match=r"object\.points: a rope rollout needs one connected rope"):
        body_from_cloud("rope", pieces, normals, {})
