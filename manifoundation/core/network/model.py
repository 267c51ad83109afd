"""The ManiFoundation CVAE (paper §III-A) and :func:`create_model`.

Training: ``forward(obj, hand, heat_gt, force_gt)`` encodes, draws z from the posterior φ_q and decodes.
Inference: :meth:`ManiFoundationNet.encode` once, then :meth:`ManiFoundationNet.decode` with K prior samples.
All inputs are already normalised (see normalize.py and inference.py).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import torch
from torch import nn

from manifoundation.core.network.config import NetworkConfig, get_config
from manifoundation.core.network.deformable_head import (
    DeformableHead,
    deformable_condition,
    is_deformable,
    motion_frame,
)
from manifoundation.core.network.encoders import Decoder, HandEncoder, ObjectEncoder, Posterior
from manifoundation.core.network.hierarchy import PointHierarchy, build_hierarchy
from manifoundation.core.network.properties import PropertyEncoder

SCALE_REFERENCE_M = 0.1  # the log-scale input channel is log(scale / SCALE_REFERENCE_M)
# Initial output of the heatmap head: a ground-truth heatmap averages about 0.02 over the points, so the
# untrained network starts there (logit) instead of at 0.5, and training spends its steps on the peaks.
HEAT_PRIOR = 0.02


@dataclass
class ObjectTensors:
    """A batch of normalised objects, all with the same point count N.

    Attributes:
        xyz: (B, N, 3) points in the unit box.
        normals: (B, N, 3) unit normals.
        motion: (B, N, 3) target motion in normalised units.
        mask: (B, N) region mask, 1 = contact allowed.
        prop_values: (B, 6) transformed property values (properties.property_tensors).
        prop_mask: (B, 6) bool, which properties are present.
        scale: (B,) metres per normalised unit.
    """

    xyz: torch.Tensor
    normals: torch.Tensor
    motion: torch.Tensor
    mask: torch.Tensor
    prop_values: torch.Tensor
    prop_mask: torch.Tensor
    scale: torch.Tensor

    def to(self, device: torch.device | str) -> ObjectTensors:
        """A copy on ``device``."""
        return ObjectTensors(**{k: v.to(device) for k, v in self.__dict__.items()})


@dataclass
class Encoded:
    """The condition ε^oh of a batch: hierarchy, per-point ε^o (B, N, C_o) and global ε^h (B, C_h); with a
    deformable head also its per-point condition (B, N, CONDITION_DIM) and which objects are deformable (B,)."""

    hierarchy: PointHierarchy
    eo: torch.Tensor
    eh: torch.Tensor
    condition: torch.Tensor | None = None
    deformable: torch.Tensor | None = None

    def rows(self, rows: slice) -> Encoded:
        """The objects ``rows`` of the batch (the hierarchy is not sliced: decoding does not read it)."""
        cond = None if self.condition is None else self.condition[rows]
        deformable = None if self.deformable is None else self.deformable[rows]
        return Encoded(self.hierarchy, self.eo[rows], self.eh[rows], cond, deformable)


class ManiFoundationNet(nn.Module):
    """Property encoder, φ_o, φ_h, φ_q and the decoders φ_c, φ_f; every part is a registered sub-module."""

    def __init__(self, config: NetworkConfig) -> None:
        super().__init__()
        self.config = config
        self.properties = PropertyEncoder(config.property_hidden, config.property_dim)
        self.object_encoder = ObjectEncoder(config)
        self.hand_encoder = HandEncoder(config)
        self.posterior = Posterior(config)
        self.contact_decoder = Decoder(config, out_dim=1, with_heatmap=False)
        self.force_decoder = Decoder(config, out_dim=3, with_heatmap=True)
        nn.init.constant_(self.contact_decoder.out.bias, math.log(HEAT_PRIOR / (1.0 - HEAT_PRIOR)))
        self.deformable_head = (
            DeformableHead(config.decoder_head[-1], config.decoder_head[-1], config.deformable_head,
                           config.deformable_motion_gain, config.deformable_frame)
            if config.deformable_head
            else None
        )

    def encode_hand(self, hand: torch.Tensor) -> torch.Tensor:
        """φ_h: hand clouds (B, M_h, 6) = (x / hand_scale_m, n) → ε^h (B, C_h)."""
        result: torch.Tensor = self.hand_encoder(hand)
        return result

    def encode(self, obj: ObjectTensors, eh: torch.Tensor, hierarchy: PointHierarchy | None = None) -> Encoded:
        """φ_o over (x, n, m, r, Γ, log-scale) → the condition ε^oh (kept as ε^o and ε^h).

        ``hierarchy``: the clouds' precomputed sampling and grouping (training); None builds it here.
        """
        if hierarchy is None:
            hierarchy = build_hierarchy(obj.xyz, self.config.levels)
        gamma = self.properties(obj.prop_values, obj.prop_mask)
        n = obj.xyz.shape[1]
        log_scale = torch.log(obj.scale / SCALE_REFERENCE_M).to(obj.xyz.dtype)
        feats = torch.cat(
            [
                obj.xyz,
                obj.normals,
                obj.motion,
                obj.mask.to(obj.xyz.dtype).unsqueeze(-1),
                gamma.unsqueeze(1).expand(-1, n, -1),
                log_scale.view(-1, 1, 1).expand(-1, n, 1),
            ],
            dim=-1,
        )
        eo = self.object_encoder(hierarchy, feats)
        if self.deformable_head is None:
            return Encoded(hierarchy, eo, eh)
        condition = deformable_condition(obj.motion, obj.prop_values, obj.prop_mask)
        if self.config.deformable_frame:
            frame = motion_frame(obj.xyz, obj.motion, self.config.deformable_frame_slides_only)
            condition = torch.cat([condition, frame], dim=-1)
        return Encoded(hierarchy, eo, eh, condition, is_deformable(obj.prop_mask))

    def decode(self, enc: Encoded, z: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        """φ_c then φ_f (fed the heatmap) for z (B, K, latent) → heatmap (B, K, N) in [0, 1], force (B, K, N, 3)."""
        _, heat, force = self.decode_logits(enc, z)
        return heat, force

    def decode_logits(self, enc: Encoded, z: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
        """:meth:`decode` with the heatmap's logits (B, K, N) first (a cross-entropy loss needs them)."""
        logit, contact_features = self.contact_decoder.with_features(enc.eo, enc.eh, z)
        logit = logit.squeeze(-1)
        heat = torch.sigmoid(logit)
        force, force_features = self.force_decoder.with_features(enc.eo, enc.eh, z, heat)
        if self.deformable_head is None:
            return logit, heat, force
        if enc.condition is None or enc.deformable is None:
            raise ValueError("a network with a deformable head decodes an encoding made by it (its condition)")
        if not bool(enc.deformable.any()):  # the head would pass every output through
            return logit, heat, force
        logit, force = self.deformable_head(contact_features, force_features, logit, force, enc.condition,
                                            enc.deformable)  # fmt: skip
        return logit, torch.sigmoid(logit), force

    def forward(
        self,
        obj: ObjectTensors,
        hand: torch.Tensor,
        heat_gt: torch.Tensor,
        force_gt: torch.Tensor,
        generator: torch.Generator | None = None,
        hierarchy: PointHierarchy | None = None,
        prior_z: torch.Tensor | None = None,
    ) -> dict[str, torch.Tensor]:
        """Training pass with the posterior.

        Args:
            obj: normalised objects.
            hand: (B, M_h, 6) hand clouds.
            heat_gt: (B, N) ground-truth heatmap M_C'.
            force_gt: (B, N, 3) ground-truth force/motion map M_S' in normalised units.
            generator: for the reparameterisation noise.
            hierarchy: precomputed sampling and grouping of ``obj.xyz`` (see hierarchy.gather_hierarchy).
            prior_z: (B, K, latent) prior samples to decode as well, on the same encoding.

        Returns:
            ``heat`` and its logits ``heat_logit`` (B, N), ``force`` (B, N, 3), ``mu`` and ``logvar``
            (B, latent); with ``prior_z`` also ``prior_heat``, ``prior_heat_logit`` (B, K, N) and ``prior_force``
            (B, K, N, 3).
        """
        enc = self.encode(obj, self.encode_hand(hand), hierarchy)
        mu, logvar = self.posterior(enc.hierarchy, enc.eo, enc.eh, heat_gt, force_gt)
        eps = torch.randn(mu.shape, generator=generator, device=mu.device, dtype=mu.dtype)
        z = mu + eps * torch.exp(0.5 * logvar)
        zs = z.unsqueeze(1) if prior_z is None else torch.cat([z.unsqueeze(1), prior_z], dim=1)
        logit, heat, force = self.decode_logits(enc, zs)
        out = {"heat": heat[:, 0], "heat_logit": logit[:, 0], "force": force[:, 0], "mu": mu, "logvar": logvar}
        if prior_z is not None:
            out.update(prior_heat=heat[:, 1:], prior_heat_logit=logit[:, 1:], prior_force=force[:, 1:])
        return out


def count_parameters(model: nn.Module) -> int:
    """Number of parameter scalars (frozen ones too: a partly frozen run describes the same model)."""
    return sum(p.numel() for p in model.parameters())


def create_model(config: str | NetworkConfig, seed: int | None = None) -> ManiFoundationNet:
    """Build an (untrained, randomly initialised) network.

    Args:
        config: a registered name (``"paper"``, ``"cpu"``) or a :class:`NetworkConfig`.
        seed: seeds the initialisation when given (the global RNG state is restored afterwards).

    Raises:
        KeyError: unknown configuration name.
    """
    cfg = get_config(config) if isinstance(config, str) else config
    if seed is None:
        return ManiFoundationNet(cfg)
    with torch.random.fork_rng(devices=[]):
        torch.manual_seed(seed)
        return ManiFoundationNet(cfg)
