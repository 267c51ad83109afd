"""Small requests for the service tests."""

from __future__ import annotations

from typing import Any

import numpy as np


def sphere(n: int = 128, radius: float = 0.04, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """``n`` points on a sphere (Fibonacci lattice) and their outward normals."""
    i = np.arange(n) + 0.5
    phi = np.arccos(1 - 2 * i / n)
    theta = np.pi * (1 + 5**0.5) * i
    normals = np.stack([np.cos(theta) * np.sin(phi), np.sin(theta) * np.sin(phi), np.cos(phi)], axis=1)
    return normals * radius, normals


def request_body(hand: str = "fake_hand", n: int = 128, **options: Any) -> dict[str, Any]:
    """A small force-closure request as plain JSON data."""
    points, normals = sphere(n)
    return {
        "object": {"points": points.tolist(), "normals": normals.tolist(), "properties": {"friction": 0.8}},
        "task": {"kind": "force_closure"},
        "robot": {"name": hand},
        "options": {"method": "direct_grasp", "timeout": 20, **options},
    }
