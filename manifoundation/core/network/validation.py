"""Checks on a :class:`manifoundation.core.network.inference.NetworkInput`; errors name the field and the problem."""

from __future__ import annotations

from typing import Any

import numpy as np

from manifoundation.core.network.properties import property_vector

MIN_POINTS = 4


def _array(value: Any, name: str, shape: tuple[int | None, ...]) -> np.ndarray:
    arr = np.asarray(value)
    if arr.ndim != len(shape) or any(s is not None and a != s for a, s in zip(arr.shape, shape, strict=True)):
        want = "(" + ", ".join("N" if s is None else str(s) for s in shape) + ")"
        raise ValueError(f"{name}: expected shape {want}, got {arr.shape}")
    if arr.dtype != np.bool_ and not np.isfinite(arr).all():
        raise ValueError(f"{name}: contains NaN or inf")
    return arr


def validate_input(inp: Any, where: str = "input") -> None:
    """Raise ValueError naming the first bad field of ``inp`` (a NetworkInput)."""
    pts = _array(inp.points, f"{where}.points", (None, 3))
    n = pts.shape[0]
    if n < MIN_POINTS:
        raise ValueError(f"{where}.points: at least {MIN_POINTS} points needed, got {n}")
    _array(inp.normals, f"{where}.normals", (n, 3))
    _array(inp.motion, f"{where}.motion", (n, 3))
    mask = _array(inp.mask, f"{where}.mask", (n,))
    if mask.dtype != np.bool_ and not np.isin(mask, (0, 1)).all():
        raise ValueError(f"{where}.mask: must be boolean (or 0/1)")
    hp = _array(inp.hand_points, f"{where}.hand_points", (None, 3))
    if hp.shape[0] < 1:
        raise ValueError(f"{where}.hand_points: empty")
    _array(inp.hand_normals, f"{where}.hand_normals", (hp.shape[0], 3))
    if not isinstance(inp.hand_key, str) or not inp.hand_key:
        raise ValueError(f"{where}.hand_key: must be a non-empty string")
    try:
        property_vector(inp.properties)
    except ValueError as exc:
        raise ValueError(f"{where}.properties: {exc}") from exc
