"""The deformable head: a residual on the heatmap logits and the motion map, open only for deformable objects.

Why a separate head: every run that trained the whole network on deformables as well lost rigid success on two
CPU cores (model card, rounds 8 and 11), and training the deformable properties' MLPs ψ alone barely moved the
deformable loss (round 12: training loss 0.54 after the first epoch, 0.52 from the second to the eighth). This
head is the capacity a deformable answer needs, placed where a rigid answer never reaches it: it reads each
point's decoder features (both decoders' last hidden layer, so the object's geometry, the hand and the latent
sample), the base outputs, the target motion at the point (and its size against the object's largest) and the
raw properties, and adds (Δ logit, Δ motion) — with ``motion_gain``, Δ motion = a · target motion + b (a per-point
gain a and residual b; see below) — but only for objects that carry a deformable property (stretch,
bending, Young's modulus or Poisson's ratio; the wire schema allows them only on cloth, rope and plasticine).
With ``frame`` it also reads each point's place in the motion's frame (:func:`motion_frame`). For every other
object the base outputs pass through unchanged, bit for bit, so weights trained with only this head
(``train_only: [deformable_head.]``) answer rigid and articulated requests exactly as the weights they started
from. Its last layer starts at zero: an untrained head is the base network.

Why a gain: the motion label at a contact is heat × the contact's post-contact motion, and for a drag or a fold
that motion is close to the target's displacement there, which the head is given. A residual alone has to
multiply its input by the heat through an MLP; trained so (round 12, and round 13's first run on verified
labels), the motions it read back at its own contacts were 0.3-0.9 of the target's displacement there (cosine
0.92-0.99), and those answers failed where the same contacts with the target's displacement succeeded (7 of 8
cloth answers). With the gain the product is one multiplication the head controls per point.
"""

from __future__ import annotations

import torch
from torch import nn

from manifoundation.core.network.layers import MLP
from manifoundation.core.network.properties import PROPERTY_NAMES

DEFORMABLE_PROPERTIES = ("stretch", "bending", "youngs_modulus", "poisson_ratio")
_DEFORMABLE_INDEX = [PROPERTY_NAMES.index(n) for n in DEFORMABLE_PROPERTIES]
CONDITION_DIM = 3 + 1 + 2 * len(PROPERTY_NAMES)  # motion, its relative size, property values and presence
FRAME_DIM = 2  # where the point sits along the mean motion and across it (`motion_frame`)
SLIDE_UNIFORMITY = 0.1  # a slide: motions differ from their mean by ≤ this × its length (answer.UNIFORM_MOTION)


def is_deformable(prop_mask: torch.Tensor) -> torch.Tensor:
    """(B, 6) property presence → (B,) bool: the object carries a deformable property."""
    return prop_mask[:, _DEFORMABLE_INDEX].any(dim=1)


def deformable_condition(motion: torch.Tensor, prop_values: torch.Tensor, prop_mask: torch.Tensor) -> torch.Tensor:
    """The head's per-point input besides the decoder features.

    Args:
        motion: (B, N, 3) normalised target motion.
        prop_values: (B, 6) transformed property values.
        prop_mask: (B, 6) bool presence.

    Returns:
        (B, N, CONDITION_DIM): the motion, its length over the object's largest, the values (0 where absent) and
        the presence flags.
    """
    length = motion.norm(dim=-1, keepdim=True)
    relative = length / length.amax(dim=1, keepdim=True).clamp_min(1e-9)
    mask = prop_mask.to(motion.dtype)
    props = torch.cat([prop_values * mask, mask], dim=-1)
    return torch.cat([motion, relative, props.unsqueeze(1).expand(-1, motion.shape[1], -1)], dim=-1)


def is_slide(motion: torch.Tensor) -> torch.Tensor:
    """(B, N, 3) target motion → (B,) bool: every point moves by about the same nonzero displacement (the mean
    distance of the motions from their mean ≤ `SLIDE_UNIFORMITY` × its length;
    `manifoundation.core.deformable.answer.is_slide`'s
    rule, which picks a slide's contacts)."""
    mean = motion.mean(dim=1, keepdim=True)
    size = mean.norm(dim=-1).squeeze(1)
    spread = (motion - mean).norm(dim=-1).mean(dim=1)
    slide: torch.Tensor = (size > 0) & (spread <= SLIDE_UNIFORMITY * size)
    return slide


def motion_frame(xyz: torch.Tensor, motion: torch.Tensor, slides_only: bool = False) -> torch.Tensor:
    """Each point's place in the frame of the object's mean target motion: how far it leads (+1: the most leading
    point, −1: the most trailing, from the centroid) and how far it sits across the motion (1: the farthest).

    Why: a slide moves every point by the same d, so the motion at a point says nothing of whether the point is a
    leading edge (a handkerchief must be pulled there) or a trailing one (pushed from there it bunches up); the
    product of a point's place and the motion's heading is one a per-point MLP would have to learn to multiply.

    Why ``slides_only``: read on every task, the frame cost the rope ten points on its usual drags and folds
    (docs/deformables.md, "Which side of the line a slid body is pulled on"), where the mean motion's heading says
    little of a point's role; zero there, the head answers those tasks from the inputs it had before.

    Args:
        xyz: (B, N, 3) normalised points. motion: (B, N, 3) normalised target motion.
        slides_only: zero frame for an object whose task is not a slide (:func:`is_slide`).

    Returns:
        (B, N, FRAME_DIM): along and across, each over its largest magnitude (0 where the mean motion vanishes).
    """
    rel = xyz - xyz.mean(dim=1, keepdim=True)
    mean = motion.mean(dim=1, keepdim=True)
    heading = mean / mean.norm(dim=-1, keepdim=True).clamp_min(1e-9)
    along = (rel * heading).sum(dim=-1, keepdim=True)
    across = (rel - along * heading).norm(dim=-1, keepdim=True)
    along = along / along.abs().amax(dim=1, keepdim=True).clamp_min(1e-9)
    across = across / across.amax(dim=1, keepdim=True).clamp_min(1e-9)
    frame = torch.cat([along, across], dim=-1)
    if slides_only:
        frame = frame * is_slide(motion).to(frame.dtype).view(-1, 1, 1)
    return frame


class DeformableHead(nn.Module):
    """Per-point MLP → (Δ logit, Δ motion), applied where :func:`is_deformable`."""

    def __init__(self, contact_features: int, force_features: int, hidden: tuple[int, ...],
                 motion_gain: bool = False, frame: bool = False) -> None:  # fmt: skip
        super().__init__()
        in_dim = contact_features + force_features + 1 + 3 + CONDITION_DIM + (FRAME_DIM if frame else 0)
        self.motion_gain = motion_gain
        self.mlp = MLP(in_dim, hidden, norm=False)
        self.out = nn.Linear(hidden[-1], 5 if motion_gain else 4)
        nn.init.zeros_(self.out.weight)
        nn.init.zeros_(self.out.bias)

    def forward(
        self,
        contact_features: torch.Tensor,
        force_features: torch.Tensor,
        logit: torch.Tensor,
        force: torch.Tensor,
        condition: torch.Tensor,
        deformable: torch.Tensor,
    ) -> tuple[torch.Tensor, torch.Tensor]:
        """Args: decoder features (B, K, N, C_c) and (B, K, N, C_f), base logits (B, K, N), base motion map
        (B, K, N, 3), condition (B, N, CONDITION_DIM, + FRAME_DIM with ``frame``), deformable (B,) bool. Returns
        the logits and the map."""
        k = logit.shape[1]
        x = torch.cat(
            [
                contact_features,
                force_features,
                logit.unsqueeze(-1),
                force,
                condition.unsqueeze(1).expand(-1, k, -1, -1),
            ],
            dim=-1,
        )
        delta = self.out(self.mlp(x))
        delta_motion = delta[..., -3:]
        if self.motion_gain:  # the condition's first three channels are the target motion at the point
            delta_motion = delta_motion + delta[..., 1:2] * condition[..., :3].unsqueeze(1)
        gate = deformable.view(-1, 1, 1)
        new_logit = torch.where(gate, logit + delta[..., 0], logit)
        new_force = torch.where(gate.unsqueeze(-1), force + delta_motion, force)
        return new_logit, new_force
