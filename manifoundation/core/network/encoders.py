"""Feature extractor (paper §III-A): object encoder φ_o (PointNet++), hand encoder φ_h (PointNet), posterior φ_q.

Per-point object input (:data:`OBJECT_INPUT_DIM` channels, normalised frame, see normalize.py):
``x (3) | n (3) | m (3) | r (1) | Γ (10) | log(scale / 0.1 m) (1)``. The last channel is ours, not the paper's:
we normalise every object to the unit box for conditioning, and the paper's objects keep their metric size
(0.05–0.4 m) which the network needs to relate the object to the (metric, un-normalised) hand.
"""

from __future__ import annotations

import torch
from torch import nn

from manifoundation.core.network.config import NetworkConfig
from manifoundation.core.network.hierarchy import PointHierarchy
from manifoundation.core.network.layers import (
    MLP,
    FeaturePropagation,
    PointNetGlobal,
    SetAbstraction,
    SplitLinear,
    norm_act,
)

GEOMETRY_DIM = 3 + 3 + 3 + 1  # x, n, m, r


def object_input_dim(config: NetworkConfig) -> int:
    """Channels of the per-point object input (geometry, Γ, log-scale)."""
    return GEOMETRY_DIM + config.property_dim + 1


class ObjectEncoder(nn.Module):
    """φ_o: PointNet++ segmentation network, per-point input → per-point feature ε^o (B, N, C_o)."""

    def __init__(self, config: NetworkConfig) -> None:
        super().__init__()
        dims = [object_input_dim(config)]
        self.sa = nn.ModuleList()
        for widths in config.sa_mlps:
            self.sa.append(SetAbstraction(dims[-1], widths, config.grouped_norm))
            dims.append(widths[-1])
        self.fp = nn.ModuleList()
        coarse = dims[-1]
        for i, widths in enumerate(config.fp_mlps):  # coarse → fine
            skip = dims[len(dims) - 2 - i]
            self.fp.append(FeaturePropagation(coarse, skip, widths))
            coarse = widths[-1]

    def forward(self, h: PointHierarchy, feats: torch.Tensor) -> torch.Tensor:
        """Args: the hierarchy of the cloud, per-point input (B, N, C_in). Returns ε^o (B, N, C_o)."""
        levels = [feats]
        for i, sa in enumerate(self.sa):
            levels.append(sa(h.xyz[i], levels[-1], h.xyz[i + 1], h.groups[i], h.radii[i]))
        cur = levels[-1]
        n_levels = len(self.sa)
        for j, fp in enumerate(self.fp):
            lvl = n_levels - j  # propagate level lvl → lvl - 1
            cur = fp(cur, levels[lvl - 1], h.up_idx[lvl - 1], h.up_weights[lvl - 1])
        return cur


class HandEncoder(nn.Module):
    """φ_h: PointNet over the hand's (x / hand_scale, n), max-pooled to a global ε^h (B, C_h)."""

    def __init__(self, config: NetworkConfig) -> None:
        super().__init__()
        self.net = PointNetGlobal(6, config.hand_mlp)

    def forward(self, hand: torch.Tensor) -> torch.Tensor:
        """Args: hand (B, M_h, 6). Returns (B, C_h)."""
        result: torch.Tensor = self.net(hand)
        return result


class Posterior(nn.Module):
    """φ_q: PointNet++ over (ε^oh, heatmap, force map) → (μ, log σ²) of z, each (B, latent_dim)."""

    def __init__(self, config: NetworkConfig) -> None:
        super().__init__()
        c_in = config.posterior_in
        self.inp = SplitLinear([config.object_feature_dim, config.hand_feature_dim, 1, 3], c_in)
        self.inp_act = norm_act(c_in)
        self.sa = nn.ModuleList()
        for widths in config.posterior_sa_mlps:
            self.sa.append(SetAbstraction(c_in, widths, config.grouped_norm))
            c_in = widths[-1]
        self.head = MLP(c_in, config.posterior_head)
        self.out = nn.Linear(self.head.out_dim, 2 * config.latent_dim)

    def forward(
        self, h: PointHierarchy, eo: torch.Tensor, eh: torch.Tensor, heat: torch.Tensor, force: torch.Tensor
    ) -> tuple[torch.Tensor, torch.Tensor]:
        """Args: eo (B, N, C_o), eh (B, C_h), heat (B, N), force (B, N, 3). Returns μ, log σ² (B, latent)."""
        x = self.inp_act(self.inp(eo, eh.unsqueeze(1), heat.unsqueeze(-1), force))
        for i, sa in enumerate(self.sa):
            x = sa(h.xyz[i], x, h.xyz[i + 1], h.groups[i], h.radii[i])
        mu, logvar = self.out(self.head(x.max(dim=1).values)).chunk(2, dim=-1)
        return mu, logvar


class Decoder(nn.Module):
    """φ_c / φ_f: PointNet over (ε^o_i, ε^h, z [, heatmap_i]) for K latent samples per object.

    The encoder features enter through a split first layer, so they are projected once and shared by the K
    samples. Output (B, K, N, out_dim), before any output activation.
    """

    def __init__(self, config: NetworkConfig, out_dim: int, with_heatmap: bool) -> None:
        super().__init__()
        dims = [config.object_feature_dim, config.hand_feature_dim, config.latent_dim]
        self.with_heatmap = with_heatmap
        local = config.decoder_local
        self.first = SplitLinear([*dims, 1] if with_heatmap else dims, local[0])
        self.first_act = norm_act(local[0])
        self.local = MLP(local[0], local[1:]) if len(local) > 1 else nn.Identity()
        head = config.decoder_head
        self.head_first = SplitLinear([local[-1], local[-1]], head[0])
        self.head_act = norm_act(head[0])
        self.head = MLP(head[0], head[1:]) if len(head) > 1 else nn.Identity()
        self.out = nn.Linear(head[-1], out_dim)

    def forward(
        self, eo: torch.Tensor, eh: torch.Tensor, z: torch.Tensor, heat: torch.Tensor | None = None
    ) -> torch.Tensor:
        """Args: eo (B, N, C_o), eh (B, C_h), z (B, K, latent), heat (B, K, N) when fed the heatmap."""
        return self.with_features(eo, eh, z, heat)[0]

    def with_features(
        self, eo: torch.Tensor, eh: torch.Tensor, z: torch.Tensor, heat: torch.Tensor | None = None
    ) -> tuple[torch.Tensor, torch.Tensor]:
        """:meth:`forward` and the last hidden layer's features (B, K, N, decoder_head[-1])."""
        p = self.first.parts
        h = p[0](eo).unsqueeze(1) + p[1](eh)[:, None, None, :] + p[2](z).unsqueeze(2)
        if self.with_heatmap:
            if heat is None:
                raise ValueError("this decoder is fed the heatmap")
            h = h + p[3](heat.unsqueeze(-1))
        local = self.local(self.first_act(h))
        glob = local.max(dim=2, keepdim=True).values
        out = self.head(self.head_act(self.head_first(local, glob)))
        result: torch.Tensor = self.out(out)
        return result, out
