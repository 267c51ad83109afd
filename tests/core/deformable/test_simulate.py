import numpy as np
import pytest

from manifoundation.core.deformable.plasticine import make_plasticine
from manifoundation.core.deformable.rope import make_rope
from manifoundation.core.deformable.simulate import SimConfig, contact_vertices, minimum_jerk, path_points, simulate


def test_minimum_jerk_profile_and_path_ends() -> None:
    assert minimum_jerk(0.0) == 0.0 and minimum_jerk(1.0) == 1.0
    assert minimum_jerk(0.5) == pytest.approx(0.5)
    start, motion = np.zeros((1, 3)), np.array([[0.2, 0.0, 0.0]])
    np.testing.assert_allclose(path_points(start, motion, 1.0, lift=0.3), motion, atol=1e-12)
    assert path_points(start, motion, 0.5, lift=0.3)[0, 2] == pytest.approx(0.06)


def test_untouched_rope_stays_where_it_lies() -> None:
    rope = make_rope(seed=0, length=0.4, properties={"friction": 0.6, "youngs_modulus": 1e6, "poisson_ratio": 0.3})
    out = simulate(rope, np.zeros(0, dtype=np.int64), np.zeros((0, 3)), SimConfig(move_seconds=0.3))
    assert out.stable
    assert np.abs(out.cloud - rope.points).max() < 3e-3


def test_dragged_rope_end_arrives_at_its_goal() -> None:
    rope = make_rope(seed=0, length=0.4, properties={"friction": 0.6, "youngs_modulus": 1e6, "poisson_ratio": 0.3})
    motion = np.array([[0.1, 0.05, 0.0]])
    out = simulate(rope, np.array([0]), motion)
    assert out.stable and out.tracking_error < 2e-3
    assert np.linalg.norm(out.cloud[0] - (rope.points[0] + motion[0])) < 0.01
    assert np.abs(out.cloud[:, 2]).max() < 0.03  # it stays on the table


def test_plasticine_keeps_a_press_and_an_elastic_body_does_not() -> None:
    props = {"friction": 0.8, "youngs_modulus": 1e6, "poisson_ratio": 0.4}
    soft = make_plasticine("sphere", seed=0, size=0.08, properties={**props, "yield_stress": 2e4})
    hard = soft.with_properties({**props, "yield_stress": 5e5})
    top = int(np.argmax(soft.points[:, 2]))
    press = np.array([[0.0, 0.0, -0.015]])
    dent = {name: simulate(b, np.array([top]), press).cloud[top, 2] - b.points[top, 2]
            for name, b in (("plastic", soft), ("elastic", hard))}  # fmt: skip
    assert dent["plastic"] < -0.01  # most of the 1.5 cm stays
    assert dent["elastic"] > -0.006  # springs back


def test_the_board_holds_a_plasticine_base_so_a_body_on_one_cube_face_stands() -> None:
    from manifoundation.core.deformable.mjcf import held_vertices

    body = make_plasticine("composite", seed=7)  # held by its lowest level alone it tips over: 4 mm mean drift
    z = body.vertices[:, 2]
    assert np.sum(z <= z.min() + 1e-9) == 4  # it touches the board with one cube's face
    held = held_vertices(body, np.zeros(0, dtype=np.int64))
    assert len(held) > 4 and np.unique(np.round(z[held], 9)).size == 2  # the bottom layer of cells
    still = simulate(body, np.zeros(0, dtype=np.int64), np.zeros((0, 3)))
    assert still.stable and np.linalg.norm(still.cloud - body.points, axis=1).mean() < 5e-4
    assert held[0] not in held_vertices(body, held[:1])  # a grasped base vertex is the grasp's
    assert len(held_vertices(make_rope(seed=0), np.zeros(0, dtype=np.int64))) == 0


def test_contacts_snap_to_the_nearest_cloud_point() -> None:
    rope = make_rope(seed=2)
    np.testing.assert_array_equal(contact_vertices(rope, rope.points[[5, 9]] + 1e-4), [5, 9])
    with pytest.raises(ValueError, match="contacts"):
        contact_vertices(rope, np.array([len(rope.points)]))
