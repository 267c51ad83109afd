"""The label-density report: coverage of the valid region and the simple rules' hits, on a known region."""

from __future__ import annotations

import numpy as np
import pytest

from research.data.label_density import label_density


def _sphere(n: int) -> np.ndarray:
    rng = np.random.default_rng(0)
    p = rng.normal(size=(n, 3))
    return p / np.linalg.norm(p, axis=1, keepdims=True)


def test_the_region_behind_a_push_is_what_the_push_rule_finds() -> None:
    pts = _sphere(2000)
    nrm = pts.copy()
    motion = np.tile([0.01, 0.0, 0.0], (2000, 1))  # pushed along +x: the contact goes on the −x side
    behind = (pts[:, 0] < -0.9).astype(np.float64)  # one valid grasp's heat: the cap facing −x
    front = (pts[:, 0] > 0.95).astype(np.float64)
    r = label_density([(pts, nrm, motion, np.stack([behind, front]), behind)])
    assert r.examples == 1 and r.set_size == 2.0
    assert r.coverage == pytest.approx(float(((behind + front) > 0).mean()))
    assert r.own == pytest.approx(float(behind.mean()))
    assert r.hit_push == 1.0
    opposite = label_density([(pts, nrm, -motion, behind[None], behind)])
    assert opposite.hit_push == 0.0  # pushed along −x the most-opposed normal faces +x, outside the region


def test_a_random_point_hits_as_often_as_the_region_is_large() -> None:
    pts = _sphere(500)
    region = (pts[:, 2] > 0.0).astype(np.float64)  # half the points
    rows = [(pts, pts, np.tile([0.0, 0.0, 0.01], (500, 1)), region[None], region)] * 400
    assert label_density(rows, seed=1).hit_random == pytest.approx(float(region.mean()), abs=0.08)
    with pytest.raises(ValueError):
        label_density([])
