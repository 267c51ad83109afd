"""Point-cloud operations of PointNet++: farthest point sampling, ball query, grouping, 3-NN interpolation.

Two back ends with the same results (up to distance ties): CPU tensors go through numpy (``fpsample``'s exact
FPS and scipy's KD-tree, measured 3.3 ms for FPS 2048→512 and 2 ms for a 32-NN ball query on 2 cores, against
≈250 ms for ``cdist`` + ``topk`` on a batch of 32); other devices use pure-torch loops. Only the exact FPS is
used: ``fpsample``'s bucket variants are faster but return a different, order-dependent subset, which would
break permutation equivariance.

Every choice here is permutation-equivariant: the FPS start point is the point farthest from the cloud's mean
(not an index), and the ball query keeps the ``k`` *nearest* neighbours within the radius (not the first
``k`` by index), padding with the nearest one.
"""

from __future__ import annotations

import fpsample
import numpy as np
import torch
from scipy.spatial import cKDTree


def fps_start_index(points: np.ndarray) -> int:
    """Permutation-invariant FPS start: the point farthest from the mean of ``points`` (N, 3)."""
    d = np.square(points - points.mean(axis=0)).sum(axis=1)
    return int(np.argmax(d))


def farthest_point_sample_np(points: np.ndarray, n: int, start: int | None = None) -> np.ndarray:
    """Exact farthest point sampling of one cloud.

    Args:
        points: (N, 3) float array.
        n: samples to keep, 1 ≤ n ≤ N.
        start: index of the first sample; ``None`` takes :func:`fps_start_index`.

    Returns:
        (n,) int64 indices into ``points``, in sampling order.
    """
    num = points.shape[0]
    if not 1 <= n <= num:
        raise ValueError(f"cannot sample {n} of {num} points")
    start = fps_start_index(points) if start is None else int(start)
    idx = fpsample.fps_sampling(np.ascontiguousarray(points, dtype=np.float32), n, start_idx=start)
    return np.asarray(idx, dtype=np.int64)


def farthest_point_sample_torch(points: torch.Tensor, n: int) -> torch.Tensor:
    """Batched exact FPS in torch (fallback for GPU tensors).

    Args:
        points: (B, N, 3).
        n: samples per cloud.

    Returns:
        (B, n) int64 indices.
    """
    b, num, _ = points.shape
    centred = points - points.mean(dim=1, keepdim=True)
    current = centred.square().sum(-1).argmax(dim=1)
    out = torch.empty(b, n, dtype=torch.long, device=points.device)
    min_d = torch.full((b, num), float("inf"), device=points.device, dtype=points.dtype)
    rows = torch.arange(b, device=points.device)
    for i in range(n):
        out[:, i] = current
        d = (points - points[rows, current].unsqueeze(1)).square().sum(-1)
        min_d = torch.minimum(min_d, d)
        current = min_d.argmax(dim=1)
    return out


def farthest_point_sample(points: torch.Tensor, n: int) -> torch.Tensor:
    """Batched FPS, (B, N, 3) → (B, n) indices; numpy on CPU, torch elsewhere."""
    if points.device.type != "cpu":
        return farthest_point_sample_torch(points, n)
    arr = points.detach().numpy()
    return torch.from_numpy(np.stack([farthest_point_sample_np(p, n) for p in arr]))


def ball_query(points: torch.Tensor, centres: torch.Tensor, radius: float, k: int) -> torch.Tensor:
    """The ``k`` nearest points within ``radius`` of each centre, padded with the nearest one.

    Args:
        points: (B, N, 3).
        centres: (B, M, 3); each centre should be one of ``points`` (then it is its own nearest).
        radius: ball radius.
        k: neighbours per centre.

    Returns:
        (B, M, k) int64 indices into ``points``.
    """
    kk = min(k, points.shape[1])
    if points.device.type == "cpu":
        p, c = points.detach().numpy(), centres.detach().numpy()
        rows = []
        for pb, cb in zip(p, c, strict=True):
            dist, idx = cKDTree(pb).query(cb, k=kk, distance_upper_bound=radius)
            idx = idx.reshape(cb.shape[0], kk)
            far = ~np.isfinite(dist.reshape(cb.shape[0], kk))
            idx = np.where(far, idx[:, :1], idx)
            rows.append(idx)
        out = torch.from_numpy(np.stack(rows).astype(np.int64))
    else:
        dist, out = torch.cdist(centres, points).topk(kk, dim=-1, largest=False)
        out = torch.where(dist > radius, out[..., :1], out)
    if kk < k:
        out = torch.cat([out, out[..., :1].expand(*out.shape[:2], k - kk)], dim=-1)
    return out


def three_nn(query: torch.Tensor, ref: torch.Tensor, eps: float = 1e-8) -> tuple[torch.Tensor, torch.Tensor]:
    """Inverse-distance weights of the 3 nearest ``ref`` points for every ``query`` point.

    Args:
        query: (B, N, 3).
        ref: (B, M, 3).

    Returns:
        idx (B, N, k) int64 and weights (B, N, k) summing to 1, k = min(3, M). A query point that coincides
        with a reference point gets (almost) all of its weight.
    """
    k = min(3, ref.shape[1])
    if query.device.type == "cpu":
        q, r = query.detach().numpy(), ref.detach().numpy()
        ds, ids = [], []
        for qb, rb in zip(q, r, strict=True):
            d, i = cKDTree(rb).query(qb, k=k)
            ds.append(np.asarray(d, dtype=np.float32).reshape(qb.shape[0], k))
            ids.append(np.asarray(i, dtype=np.int64).reshape(qb.shape[0], k))
        dist, idx = torch.from_numpy(np.stack(ds)), torch.from_numpy(np.stack(ids))
    else:
        dist, idx = torch.cdist(query, ref).topk(k, dim=-1, largest=False)
    w = 1.0 / (dist.to(query.dtype).square() + eps)
    return idx, w / w.sum(dim=-1, keepdim=True)


def gather_points(features: torch.Tensor, idx: torch.Tensor) -> torch.Tensor:
    """Index per-point features with batched indices.

    Args:
        features: (B, N, C).
        idx: (B, *S) int64 indices into N.

    Returns:
        (B, *S, C).
    """
    b, n, c = features.shape
    offset = (torch.arange(b, device=idx.device) * n).view(b, *([1] * (idx.dim() - 1)))
    flat = features.reshape(b * n, c)[(idx + offset).reshape(-1)]
    return flat.view(*idx.shape, c)


def interpolate(features: torch.Tensor, idx: torch.Tensor, weights: torch.Tensor) -> torch.Tensor:
    """Weighted sum of gathered features: (B, M, C) with idx/weights (B, N, k) → (B, N, C)."""
    out = gather_points(features, idx[..., 0]) * weights[..., :1]
    for j in range(1, idx.shape[-1]):
        out = out + gather_points(features, idx[..., j]) * weights[..., j : j + 1]
    return out
