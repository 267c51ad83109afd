"""Point operations against the torch fallbacks and hand-checked facts."""

from __future__ import annotations

import numpy as np
import torch

from manifoundation.core.network.point_ops import (
    ball_query,
    farthest_point_sample,
    farthest_point_sample_torch,
    gather_points,
    interpolate,
    three_nn,
)
from manifoundation.core.network.resample import resample


def cloud(b: int, n: int, seed: int = 0) -> torch.Tensor:
    return torch.rand(b, n, 3, generator=torch.Generator().manual_seed(seed))


def test_fps_numpy_matches_torch_and_spreads_points() -> None:
    pts = cloud(2, 700)
    a, b = farthest_point_sample(pts, 64), farthest_point_sample_torch(pts, 64)
    for i in range(2):
        assert set(a[i].tolist()) == set(b[i].tolist())
        assert len(set(a[i].tolist())) == 64
    # a farthest point sample is far better spread than the minimum spacing of a random subset
    sel = pts[0, a[0]]
    d = torch.cdist(sel, sel) + torch.eye(64) * 10
    rnd = pts[0, :64]
    d_rnd = torch.cdist(rnd, rnd) + torch.eye(64) * 10
    assert d.min() > d_rnd.min()


def test_ball_query_nearest_within_radius() -> None:
    pts = cloud(1, 500)
    centres = gather_points(pts, torch.tensor([[0, 10, 20]]))
    idx = ball_query(pts, centres, radius=0.15, k=16)
    assert idx.shape == (1, 3, 16)
    assert idx[0, :, 0].tolist() == [0, 10, 20]  # each centre is its own nearest neighbour
    d = (gather_points(pts, idx) - centres.unsqueeze(2)).norm(dim=-1)
    assert (d <= 0.15 + 1e-6).all()
    ref = torch.cdist(centres, pts)[0]
    for c in range(3):
        inside = (ref[c] <= 0.15).nonzero().flatten()
        want = inside[ref[c, inside].argsort()[:16]].tolist()
        assert set(idx[0, c].tolist()) == set(want)


def test_ball_query_pads_with_nearest_and_handles_k_above_n() -> None:
    pts = torch.tensor([[[0.0, 0, 0], [1.0, 0, 0], [0.01, 0, 0]]])
    idx = ball_query(pts, pts[:, :1], radius=0.1, k=5)
    assert idx.tolist() == [[[0, 2, 0, 0, 0]]]


def test_three_nn_interpolation() -> None:
    ref = cloud(1, 50)
    feats = torch.randn(1, 50, 4)
    idx, w = three_nn(ref, ref)
    torch.testing.assert_close(w.sum(-1), torch.ones(1, 50))
    torch.testing.assert_close(interpolate(feats, idx, w), feats, atol=1e-4, rtol=0)


def test_resample_round_trip() -> None:
    rng = np.random.default_rng(0)
    for n in (100, 256, 1000):
        pts = rng.random((n, 3))
        r = resample(pts, 256)
        assert r.indices.shape == (256,)
        values = pts[r.indices][None]  # the model point's own coordinates as its "output"
        back = r.map_back(values)[0]
        if n <= 256:
            np.testing.assert_array_equal(back, pts)
        else:
            kept = r.indices
            np.testing.assert_allclose(back[kept], pts[kept], atol=1e-6)


def test_precomputed_hierarchy_equals_the_built_one_under_rotation_and_scale() -> None:
    from scipy.spatial.transform import Rotation

    from manifoundation.core.network.config import get_config
    from manifoundation.core.network.hierarchy import build_hierarchy, gather_hierarchy, index_hierarchy

    levels = get_config("cpu1k").levels
    raw = cloud(2, 1024, seed=3).numpy() * np.array([0.3, 0.1, 0.05], dtype=np.float32)  # an elongated cloud
    index = [index_hierarchy(p, levels) for p in raw]  # once, on the metric cloud
    rot = Rotation.random(random_state=0).as_matrix().astype(np.float32)
    moved = torch.as_tensor((raw @ rot.T - raw.mean(axis=(0, 1))) / 0.3)  # rotated, shifted, scaled
    built, gathered = build_hierarchy(moved, levels), gather_hierarchy(moved, index, levels)
    for lv in range(len(levels)):
        torch.testing.assert_close(gathered.xyz[lv + 1], built.xyz[lv + 1])
        assert torch.equal(gathered.groups[lv], built.groups[lv])  # the radius applied to the moved cloud
        assert torch.equal(gathered.up_idx[lv], built.up_idx[lv])
        torch.testing.assert_close(gathered.up_weights[lv], built.up_weights[lv], atol=1e-5, rtol=1e-4)
