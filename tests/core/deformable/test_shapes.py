import numpy as np
import pytest

from manifoundation.core.deformable.cloth import make_cloth
from manifoundation.core.deformable.plasticine import make_plasticine
from manifoundation.core.deformable.rope import make_rope
from manifoundation.core.deformable.shapes import KINDS, make_body


@pytest.mark.parametrize(("material", "kind"), [(m, k) for m, kinds in KINDS.items() for k in kinds])
def test_every_shape_is_a_valid_cloud_on_the_table(material: str, kind: str) -> None:
    body = make_body(material, kind, seed=3)
    assert len(body.points) >= 64  # the contract's smallest cloud
    assert body.vertices[:, 2].min() > 0  # above the table
    np.testing.assert_allclose(np.linalg.norm(body.normals, axis=1), 1.0)
    assert body.measure() > 0
    assert body.id.startswith(kind)
    # same seed, same body
    np.testing.assert_array_equal(make_body(material, kind, seed=3).vertices, body.vertices)


def test_square_cloth_remesh_keeps_its_area() -> None:
    body = make_cloth("square", seed=0, size=0.4)
    assert body.measure() == pytest.approx(0.16, rel=0.03)
    assert body.size == pytest.approx(0.4, rel=1e-6)


def test_disc_cloth_area_is_close_to_the_ellipse() -> None:
    body = make_cloth("disc", seed=0, size=0.4)
    (w, h) = np.ptp(body.points[:, :2], axis=0)
    assert body.measure() == pytest.approx(np.pi * w * h / 4, rel=0.05)


def test_rope_has_the_requested_length() -> None:
    body = make_rope(seed=1, length=0.6)
    assert body.measure() == pytest.approx(0.6, rel=2e-3)  # the curved rod: volume / cross-section


def test_plasticine_normals_point_outward_and_volume_is_near_the_sphere() -> None:
    body = make_plasticine("sphere", seed=0, size=0.08, cells=10)
    centre = body.vertices.mean(axis=0)
    outward = np.einsum("ij,ij->i", body.normals, body.points - centre)
    assert np.all(outward > 0)
    # the lattice solid, rescaled to the size, is a staircase sphere: its volume within 25 % of the ball's
    assert body.measure() == pytest.approx(np.pi / 6 * 0.08**3, rel=0.25)
