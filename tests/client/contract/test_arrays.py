"""Typed-binary and nested-list arrays: round trips and the safety rules."""

from __future__ import annotations

from typing import Annotated

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp
from pydantic import BaseModel, ValidationError

from manifoundation.contract.arrays import WIRE_DTYPES, decode_typed, encode_typed, spec


class Holder(BaseModel):
    points: Annotated[np.ndarray, spec("N", 3)]
    mask: Annotated[np.ndarray, spec("N", kind="bool")] | None = None


@pytest.mark.parametrize("name", sorted(WIRE_DTYPES))
def test_typed_round_trip_every_dtype(name: str) -> None:
    array = (np.arange(12) % 2).astype(WIRE_DTYPES[name]).reshape(4, 3)
    decoded = decode_typed(encode_typed(array))
    assert decoded.dtype == WIRE_DTYPES[name]
    np.testing.assert_array_equal(decoded, array)


@given(hnp.arrays(np.float32, hnp.array_shapes(min_dims=1, max_dims=3, max_side=6)))
def test_typed_round_trip_is_exact(array: np.ndarray) -> None:
    np.testing.assert_array_equal(decode_typed(encode_typed(array)), array)


def test_object_dtype_is_refused() -> None:
    with pytest.raises(ValueError, match="not allowed"):
        decode_typed({"dtype": "object", "shape": [1], "data": b"\x00" * 8})


def test_size_mismatch_is_refused() -> None:
    with pytest.raises(ValueError, match="needs 24 bytes, got 20"):
        decode_typed({"dtype": "float64", "shape": [3], "data": b"\x00" * 20})


@pytest.mark.parametrize("shape", [[-1], [1.5], "3", [True]])
def test_bad_shapes_are_refused(shape: object) -> None:
    with pytest.raises(ValueError, match="shape"):
        decode_typed({"dtype": "uint8", "shape": shape, "data": b""})


def test_element_cap() -> None:
    with pytest.raises(ValueError, match="more than the limit"):
        decode_typed({"dtype": "uint8", "shape": [10, 10], "data": b"\x00" * 100}, max_elements=99)


def test_field_accepts_lists_typed_and_numpy_alike() -> None:
    array = np.random.default_rng(0).normal(size=(5, 3))
    for value in (array, array.tolist(), encode_typed(array)):
        np.testing.assert_allclose(Holder(points=value).points, array)


def test_json_mode_gives_lists_python_mode_keeps_numpy() -> None:
    holder = Holder(points=np.zeros((2, 3)), mask=[1, 0])
    assert holder.model_dump(mode="json")["points"] == [[0.0] * 3] * 2
    assert isinstance(holder.model_dump()["points"], np.ndarray)
    assert holder.mask is not None and holder.mask.dtype == np.bool_


@pytest.mark.parametrize(
    ("value", "message"),
    [
        ([[1, 2]], "expected shape (N, 3), got (1, 2)"),
        ([[1, 2, 3], [1, 2]], "ragged"),
        ([[1, 2, float("nan")]], "NaN or inf at index [0, 2]"),
        ([[1, 2, float("inf")]], "NaN or inf"),
        ("abc", "expected an array"),
        ([["a", "b", "c"]], "must hold numbers"),
    ],
)
def test_field_errors_name_the_problem(value: object, message: str) -> None:
    with pytest.raises(ValidationError) as info:
        Holder(points=value)
    assert message in str(info.value)


@given(st.lists(st.integers(min_value=-3, max_value=3), min_size=1, max_size=20))
def test_mask_accepts_only_zero_and_one(values: list[int]) -> None:
    points = np.zeros((len(values), 3))
    if set(values) <= {0, 1}:
        assert Holder(points=points, mask=values).mask is not None
    else:
        with pytest.raises(ValidationError, match="values must be 0 or 1"):
            Holder(points=points, mask=values)
