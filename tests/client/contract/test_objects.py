"""Validation of objects: every rule of the contract fails with a message naming the field."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from pydantic import ValidationError

from manifoundation.contract import MATERIAL_PROPERTIES, PROPERTY_NAMES, Material, ObjectIn
from manifoundation.contract.validation import field_errors

RNG = np.random.default_rng(0)
POINTS = RNG.normal(size=(100, 3))
NORMALS = POINTS / np.linalg.norm(POINTS, axis=1, keepdims=True)


def _errors(body: dict[str, Any]) -> list[tuple[str, str]]:
    with pytest.raises(ValidationError) as info:
        ObjectIn.model_validate(body)
    return [(e.field, e.problem) for e in field_errors(info.value)]


def test_valid_object_defaults() -> None:
    obj = ObjectIn(points=POINTS, normals=NORMALS)
    assert obj.material is Material.RIGID
    assert obj.properties.friction == 0.5
    assert obj.num_points == 100


@given(st.integers(min_value=1, max_value=300))
def test_point_count_bounds(n: int) -> None:
    points = np.random.default_rng(0).normal(size=(n, 3))
    if n >= 64:
        assert ObjectIn(points=points).num_points == n
    else:
        assert _errors({"points": points}) == [("points", f"{n} points given, need 64..200000")]


def test_collinear_or_coincident_points_are_refused() -> None:
    line = np.outer(np.linspace(0, 1, 100), [1.0, 2.0, 3.0])
    assert _errors({"points": line}) == [
        ("points", "all points lie on one line (or coincide); an object needs a 2D or 3D extent")
    ]
    assert _errors({"points": np.zeros((100, 3))})[0][0] == "points"
    plate = np.random.default_rng(0).normal(size=(100, 3)) * [1.0, 1.0, 0.0]  # a flat object is fine
    assert ObjectIn(points=plate).num_points == 100


def test_too_many_points() -> None:
    assert _errors({"points": np.zeros((200_001, 3), dtype=np.float32)})[0][0] == "points"


def test_normals_shape_mismatch() -> None:
    [(field, problem)] = _errors({"points": POINTS, "normals": NORMALS[:80]})
    assert field == "normals" and "does not match points" in problem


def test_zero_length_normal() -> None:
    normals = NORMALS.copy()
    normals[7] = 0
    assert _errors({"points": POINTS, "normals": normals}) == [("normals", "zero-length normal at index 7")]


def test_normals_are_made_unit() -> None:
    obj = ObjectIn(points=POINTS, normals=NORMALS * 3)
    assert obj.normals is not None
    np.testing.assert_allclose(np.linalg.norm(obj.normals, axis=1), 1)


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_non_finite_points(bad: float) -> None:
    points = POINTS.copy()
    points[3, 1] = bad
    [(field, problem)] = _errors({"points": points})
    assert field == "points" and "NaN or inf at index [3, 1]" in problem


def test_mask_rules() -> None:
    assert _errors({"points": POINTS, "region_mask": np.zeros(100)}) == [
        ("region_mask", "all zero, no point may be touched")
    ]
    assert _errors({"points": POINTS, "region_mask": np.full(100, 0.5)})[0] == ("region_mask", "values must be 0 or 1")
    assert "expected (100,)" in _errors({"points": POINTS, "region_mask": np.ones(99)})[0][1]


@given(st.floats(allow_nan=False, allow_infinity=False, min_value=-10, max_value=10))
def test_friction_range(mu: float) -> None:
    body = {"points": POINTS, "properties": {"friction": mu}}
    if 0 < mu <= 5:
        assert ObjectIn.model_validate(body).properties.friction == mu
    else:
        assert _errors(body)[0][0] == "properties.friction"


@given(st.sampled_from(list(Material)), st.sets(st.sampled_from(PROPERTY_NAMES)))
def test_material_property_combinations(material: Material, names: set[str]) -> None:
    values = {
        "friction": 0.4,
        "density": 800,
        "stretch": 100,
        "bending": 0.1,
        "youngs_modulus": 1e5,
        "poisson_ratio": 0.3,
    }
    body: dict[str, Any] = {
        "points": POINTS,
        "material": material.value,
        "properties": {name: values[name] for name in names},
    }
    if material is Material.ARTICULATED:
        body["joint"] = {"type": "revolute", "axis": [0, 0, 1], "part_mask": np.arange(100) < 50}
    extra = names - MATERIAL_PROPERTIES[material]
    if extra:
        [(field, problem)] = _errors(body)
        assert field == "properties" and sorted(extra)[0] in problem and material.value in problem
    else:
        assert set(ObjectIn.model_validate(body).properties.present()) == names | {"friction"}


def test_articulated_needs_a_joint_and_others_refuse_one() -> None:
    assert _errors({"points": POINTS, "material": "articulated"}) == [("joint", "required for material 'articulated'")]
    joint = {"type": "prismatic", "axis": [1, 0, 0], "part_mask": np.ones(100)}
    assert _errors({"points": POINTS, "joint": joint})[0][0] == "joint"


def test_joint_axis_must_be_nonzero() -> None:
    joint = {"type": "revolute", "axis": [0, 0, 0], "part_mask": np.ones(100)}
    [(field, problem)] = _errors({"points": POINTS, "material": "articulated", "joint": joint})
    assert field == "joint.axis" and "zero length" in problem


def test_mesh_faces_must_index_vertices() -> None:
    mesh = {"vertices": np.eye(4, 3), "faces": [[0, 1, 2], [0, 1, 3], [0, 2, 3], [1, 2, 9]]}
    [(field, problem)] = _errors({"points": POINTS, "mesh": mesh})
    assert field == "mesh" and "outside 0..3" in problem


def test_unknown_fields_are_refused() -> None:
    assert _errors({"points": POINTS, "colour": "red"})[0][0] == "colour"
