"""Building blocks: shared MLPs, set abstraction, feature propagation, PointNet pooling.

Tensors are channels-last, batch first: per-point features are (B, N, C). Every hidden layer is
Linear → BatchNorm → ReLU, as in PointNet++. BatchNorm normalises each channel over all points of the batch,
which removes the per-channel offsets that are constant over an object's points (the hand feature, z, the
global pool) and leaves the per-point variation at unit scale. We first used LayerNorm (per point, over
channels) to keep training batch-independent: on the overfit test the per-point signal then stayed ~10 % of
the constant part and the heatmap collapsed to its mean (measured); with BatchNorm it is learnt. At inference
(eval mode) BatchNorm uses its running statistics, so outputs do not depend on batch-mates or point order.

A layer whose input is a concatenation ``[a, b, ...]`` is written as a sum of projections ``W_a a + W_b b``
(:class:`SplitLinear`): the same function, but a term that is shared (the hand feature across points, the
encoder features across K latent samples) is projected once and broadcast.
"""

from __future__ import annotations

from collections.abc import Sequence

import torch
import torch.nn.functional as F
from torch import nn

from manifoundation.core.network.point_ops import gather_points, interpolate


class ChannelBatchNorm(nn.BatchNorm1d):
    """BatchNorm over the last dimension of a (..., C) tensor (statistics over every other dimension)."""

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return super().forward(x.reshape(-1, x.shape[-1])).view(x.shape)


def norm_act(width: int, norm: bool = True) -> nn.Sequential:
    """BatchNorm (unless ``norm`` is False) followed by a ReLU.

    Not in place: the norm's output is a view, and an in-place ReLU on it made autograd copy the whole
    (grouped, largest) tensor back in the backward pass (measured: a fifth of a training step).
    """
    if norm:
        return nn.Sequential(ChannelBatchNorm(width), nn.ReLU())
    return nn.Sequential(nn.ReLU())


class MLP(nn.Module):
    """Shared (per-point) MLP over the last dimension.

    Args:
        in_dim: input channels.
        widths: output width of each layer.
        last_act: apply norm + ReLU after the last layer too (``False`` for output heads).
        norm: use BatchNorm (``False``: Linear → ReLU only).
    """

    def __init__(self, in_dim: int, widths: Sequence[int], last_act: bool = True, norm: bool = True) -> None:
        super().__init__()
        layers: list[nn.Module] = []
        for i, w in enumerate(widths):
            layers.append(nn.Linear(in_dim, w))
            if last_act or i < len(widths) - 1:
                layers.append(norm_act(w, norm))
            in_dim = w
        self.net = nn.Sequential(*layers)
        self.out_dim = in_dim

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        result: torch.Tensor = self.net(x)
        return result


class SplitLinear(nn.Module):
    """``Linear(concat(x_1, ..., x_n))`` computed as a broadcast sum of per-input projections.

    Args:
        in_dims: width of each input.
        out_dim: output width.
    """

    def __init__(self, in_dims: Sequence[int], out_dim: int) -> None:
        super().__init__()
        self.parts = nn.ModuleList(nn.Linear(d, out_dim, bias=(i == 0)) for i, d in enumerate(in_dims))

    def forward(self, *xs: torch.Tensor) -> torch.Tensor:
        out = self.parts[0](xs[0])
        for lin, x in zip(list(self.parts)[1:], xs[1:], strict=True):
            out = out + lin(x)
        result: torch.Tensor = out
        return result


class SetAbstraction(nn.Module):
    """PointNet++ set abstraction: group neighbours of each centroid, shared MLP, max-pool.

    The first layer sees ``[(p_j - c) / r, f_j]`` for neighbour j of centroid c. It is linear, so it is
    computed as ``(W_x p_j / r + W_f f_j) - W_x c / r``: the first term per source point before grouping (a
    point belongs to several groups), the second per centroid. Same function, less work.

    Args:
        in_dim: per-point feature channels of the source level.
        widths: MLP widths applied to every (centroid, neighbour) pair before the max-pool.
        grouped_norm: BatchNorm inside the per-neighbour layers; if False they are Linear → ReLU and one
            BatchNorm follows the max-pool (cheaper: the grouped tensors are the largest in the network).
    """

    def __init__(self, in_dim: int, widths: Sequence[int], grouped_norm: bool = True) -> None:
        super().__init__()
        self.lin_x = nn.Linear(3, widths[0])
        self.lin_f = nn.Linear(in_dim, widths[0], bias=False)
        self.act = norm_act(widths[0], grouped_norm)
        self.rest = MLP(widths[0], widths[1:], norm=grouped_norm) if len(widths) > 1 else nn.Identity()
        self.post = nn.Identity() if grouped_norm else ChannelBatchNorm(widths[-1])
        self.out_dim = widths[-1]

    def forward(
        self,
        xyz: torch.Tensor,
        feats: torch.Tensor,
        new_xyz: torch.Tensor,
        group: torch.Tensor,
        radius: float,
    ) -> torch.Tensor:
        """Args: xyz (B, N, 3), feats (B, N, C), new_xyz (B, M, 3), group (B, M, k). Returns (B, M, C')."""
        w_x = self.lin_x.weight
        per_point = self.lin_f(feats) + F.linear(xyz / radius, w_x)
        per_centre = F.linear(new_xyz / radius, w_x) - self.lin_x.bias
        h = gather_points(per_point, group) - per_centre.unsqueeze(2)
        # max, not amax: its backward scatters into the arg-max only (amax's spreads over ties: 2.5x slower)
        result: torch.Tensor = self.post(self.rest(self.act(h)).max(dim=2).values)
        return result


class FeaturePropagation(nn.Module):
    """PointNet++ feature propagation: 3-NN interpolation of coarse features, concatenated with skip features.

    Args:
        coarse_dim: channels of the coarse level.
        skip_dim: channels of the fine level's skip features.
        widths: MLP widths.
    """

    def __init__(self, coarse_dim: int, skip_dim: int, widths: Sequence[int]) -> None:
        super().__init__()
        self.first = SplitLinear([skip_dim, coarse_dim], widths[0])
        self.act = norm_act(widths[0])
        self.rest = MLP(widths[0], widths[1:]) if len(widths) > 1 else nn.Identity()
        self.out_dim = widths[-1]

    def forward(
        self, coarse: torch.Tensor, skip: torch.Tensor, idx: torch.Tensor, weights: torch.Tensor
    ) -> torch.Tensor:
        """Args: coarse (B, M, C), skip (B, N, C_s), idx/weights (B, N, 3). Returns (B, N, C')."""
        # Linear(interp(coarse)) == interp(Linear(coarse)): project on the (fewer) coarse points first.
        lin_skip, lin_coarse = self.first.parts[0], self.first.parts[1]
        h = lin_skip(skip) + interpolate(lin_coarse(coarse), idx, weights)
        result: torch.Tensor = self.rest(self.act(h))
        return result


class PointNetGlobal(nn.Module):
    """PointNet: shared MLP then max-pool over points, (B, N, C) → (B, C')."""

    def __init__(self, in_dim: int, widths: Sequence[int]) -> None:
        super().__init__()
        self.mlp = MLP(in_dim, widths)
        self.out_dim = self.mlp.out_dim

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        result: torch.Tensor = self.mlp(x).max(dim=-2).values
        return result
