"""Network configurations: one frozen dataclass per variant, kept in a small registry (timm style).

``paper`` reproduces the size the paper reports (about 5 M parameters); ``cpu`` is a smaller one sized by
measurement with ``mani-lab bench network``, ``cpu1k`` the same on 1 024 points, and the shipped weights'
configuration is ``cpu1k_deformable_slide_frame`` (``cpu1k`` with the deformable head; its model card names it).
Look a configuration up with :func:`get_config`; build a model with
:func:`manifoundation.core.network.model.create_model`.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any


@dataclass(frozen=True)
class LevelConfig:
    """One set-abstraction level of the shared point hierarchy.

    Attributes:
        npoint: centroids kept by farthest point sampling at this level.
        radius: ball-query radius in the normalised frame (the object spans the unit box).
        nsample: neighbours grouped per centroid (the nearest ``nsample`` inside ``radius``).
    """

    npoint: int
    radius: float
    nsample: int


@dataclass(frozen=True)
class NetworkConfig:
    """All sizes of the ManiFoundation network (paper §III-A).

    Channel tuples list hidden and output widths of shared MLPs; the input width is implied.
    """

    name: str
    # --- input ---
    num_points: int = 2048  # every object is resampled to this many points (see inference.py)
    hand_scale_m: float = 0.2  # hand point clouds (palm frame, metres) are divided by this constant
    # --- shared point hierarchy (object encoder φ_o and posterior φ_q) ---
    levels: tuple[LevelConfig, ...] = (
        LevelConfig(512, 0.1, 32),
        LevelConfig(128, 0.2, 32),
        LevelConfig(32, 0.4, 16),
    )
    # --- physical-property encoder ψ_i: R → R^property_dim ---
    property_hidden: int = 32
    property_dim: int = 10
    # --- PointNet++ set abstractions (φ_o and φ_q) ---
    grouped_norm: bool = True  # BatchNorm inside the per-neighbour layers (False: after the max-pool only)
    # --- object encoder φ_o (PointNet++) ---
    sa_mlps: tuple[tuple[int, ...], ...] = ((32, 32, 64), (64, 64, 128), (128, 128, 256))
    fp_mlps: tuple[tuple[int, ...], ...] = ((256, 256), (128, 128), (128, 128))  # coarse → fine
    # --- hand encoder φ_h (PointNet, max-pooled) ---
    hand_mlp: tuple[int, ...] = (64, 128, 128)
    # --- CVAE ---
    latent_dim: int = 64
    posterior_in: int = 64  # per-point projection of (ε^oh, heatmap, force map) before the SA levels
    posterior_sa_mlps: tuple[tuple[int, ...], ...] = ((64, 64), (128, 128), (128, 256))
    posterior_head: tuple[int, ...] = (256,)
    decoder_local: tuple[int, ...] = (128, 128)  # per-point MLP of φ_c / φ_f before the global max-pool
    decoder_head: tuple[int, ...] = (128, 64)  # after concatenating the global feature
    # hidden widths of the deformable head (manifoundation.core.network.deformable_head); () = none
    deformable_head: tuple[int, ...] = ()
    # the head's motion as gain · target motion + residual (True) or as a residual alone (False, round 12)
    deformable_motion_gain: bool = False
    # the head also reads each point's place along and across the mean motion (deformable_head.motion_frame)
    deformable_frame: bool = False
    # ... only where the task is a slide (deformable_head.is_slide); zero on every other task
    deformable_frame_slides_only: bool = False
    # --- loss of Eq. (3) ---
    # The paper does not state λ_C, λ_S, λ_KL; these defaults are ours (heatmap and force map weighted
    # equally, a small KL weight as usual for CVAEs) and are recorded in every model card.
    lambda_c: float = 1.0
    lambda_s: float = 1.0
    lambda_kl: float = 1e-3

    def __post_init__(self) -> None:
        if len(self.sa_mlps) != len(self.levels) or len(self.fp_mlps) != len(self.levels):
            raise ValueError(f"config {self.name!r}: sa_mlps, fp_mlps and levels must have the same length")
        if len(self.posterior_sa_mlps) > len(self.levels):
            raise ValueError(f"config {self.name!r}: the posterior uses at most {len(self.levels)} levels")
        npoints = [lv.npoint for lv in self.levels]
        if npoints != sorted(npoints, reverse=True) or npoints[0] > self.num_points:
            raise ValueError(f"config {self.name!r}: level npoints must decrease and not exceed num_points")

    @property
    def object_feature_dim(self) -> int:
        """Width of the per-point object feature ε^o."""
        return self.fp_mlps[-1][-1]

    @property
    def hand_feature_dim(self) -> int:
        """Width of the global hand feature ε^h."""
        return self.hand_mlp[-1]

    def to_dict(self) -> dict[str, Any]:
        """Plain-JSON form (tuples become lists), as stored in model cards."""
        result: dict[str, Any] = json_ready(dataclasses.asdict(self))
        return result

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> NetworkConfig:
        """Inverse of :meth:`to_dict`."""
        d = config_with_defaults(data)
        d["levels"] = tuple(LevelConfig(**lv) for lv in d["levels"])
        for key in ("sa_mlps", "fp_mlps", "posterior_sa_mlps"):
            d[key] = tuple(tuple(m) for m in d[key])
        for key in ("hand_mlp", "posterior_head", "decoder_local", "decoder_head", "deformable_head"):
            d[key] = tuple(d[key])
        return cls(**d)


def config_with_defaults(data: dict[str, Any]) -> dict[str, Any]:
    """A stored config dict with the fields added since it was stored set to their defaults (plain JSON)."""
    out = dict(data)
    for f in dataclasses.fields(NetworkConfig):
        if f.name not in out and f.default is not dataclasses.MISSING:
            out[f.name] = json_ready(f.default)
    return out


def json_ready(value: Any) -> Any:
    """Turn tuples into lists recursively so that a config compares equal to its JSON round trip."""
    if isinstance(value, dict):
        return {k: json_ready(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [json_ready(v) for v in value]
    return value


_REGISTRY: dict[str, Callable[[], NetworkConfig]] = {}


def register_config(fn: Callable[[], NetworkConfig]) -> Callable[[], NetworkConfig]:
    """Register a zero-argument factory under the name of the configuration it returns."""
    name = fn().name
    if name in _REGISTRY:
        raise ValueError(f"network config {name!r} registered twice")
    _REGISTRY[name] = fn
    return fn


def list_configs() -> list[str]:
    """Names of every registered configuration, sorted."""
    return sorted(_REGISTRY)


def get_config(name: str) -> NetworkConfig:
    """The configuration registered as ``name``.

    Raises:
        KeyError: ``name`` is not registered (the message lists the known names).
    """
    if name not in _REGISTRY:
        raise KeyError(f"unknown network config {name!r}; known: {', '.join(list_configs())}")
    return _REGISTRY[name]()


@register_config
def paper() -> NetworkConfig:
    """The paper's size: about 5 M parameters (paper §VI: "about 5 million parameters")."""
    return NetworkConfig(
        name="paper",
        levels=(
            LevelConfig(512, 0.1, 32),
            LevelConfig(256, 0.2, 32),
            LevelConfig(64, 0.4, 32),
            LevelConfig(16, 0.8, 16),
        ),
        sa_mlps=((64, 64, 128), (128, 128, 256), (256, 256, 512), (512, 512, 1024)),
        fp_mlps=((512, 512), (512, 256), (256, 256), (256, 256)),
        hand_mlp=(64, 128, 256),
        posterior_in=128,
        posterior_sa_mlps=((128, 128), (256, 256), (256, 512)),
        posterior_head=(512, 256),
        decoder_local=(256, 256),
        decoder_head=(256, 128),
    )


@register_config
def cpu() -> NetworkConfig:
    """The CPU configuration, sized for the latency goals on 2 CPU cores (``mani-lab bench network``).

    Against the dataclass defaults, measured per object (N = 2048, batch 8, 1 thread, CPU time): no norm
    inside the grouped layers, 16 neighbours at level 1, a 64-wide ε^o and narrower decoders took the cost
    from ≈55 ms to ≈27 ms with 0.63 M parameters.
    """
    return NetworkConfig(
        name="cpu",
        levels=(LevelConfig(512, 0.1, 16), LevelConfig(128, 0.2, 32), LevelConfig(32, 0.4, 16)),
        grouped_norm=False,
        fp_mlps=((256, 256), (128, 128), (128, 64)),
        decoder_local=(64, 64),
        decoder_head=(64, 32),
    )


@register_config
def cpu1k() -> NetworkConfig:
    """``cpu`` on 1 024 points (levels 256/64/16), for training on two CPU cores.

    Measured (batch 16, one thread, CPU time of forward + backward, 2026-12-01): ``cpu`` 1.63 s a step,
    ``cpu1k`` 0.73 s; 1 024 points with ``cpu``'s 512/128/32 levels 1.67 s (the level-1 groups dominate).
    The contact kernel is 5 % of the object's size wide, so 1 024 points still put ≥ 10 inside a contact.
    """
    return dataclasses.replace(
        cpu(),
        name="cpu1k",
        num_points=1024,
        levels=(LevelConfig(256, 0.1, 16), LevelConfig(64, 0.2, 32), LevelConfig(16, 0.4, 16)),
    )


@register_config
def cpu1k_deformable() -> NetworkConfig:
    """``cpu1k`` with the deformable head (64, 64): the shipped rigid weights plus a head only deformable
    objects reach (manifoundation.core.network.deformable_head)."""
    return dataclasses.replace(cpu1k(), name="cpu1k_deformable", deformable_head=(64, 64))


@register_config
def cpu1k_deformable_gain() -> NetworkConfig:
    """``cpu1k_deformable`` whose head adds a per-point gain on the target motion to the motion map
    (manifoundation.core.network.deformable_head): a post-contact motion is mostly the target's displacement at the
    contact."""
    return dataclasses.replace(cpu1k_deformable(), name="cpu1k_deformable_gain", deformable_motion_gain=True)


@register_config
def cpu1k_deformable_frame() -> NetworkConfig:
    """``cpu1k_deformable_gain`` whose head also reads where each point sits along and across the mean target
    motion (manifoundation.core.network.deformable_head.motion_frame): under a slide every point moves alike, and only
    its place
    says whether it is a leading edge."""
    return dataclasses.replace(cpu1k_deformable_gain(), name="cpu1k_deformable_frame", deformable_frame=True)


@register_config
def cpu1k_deformable_slide_frame() -> NetworkConfig:
    """``cpu1k_deformable_frame`` whose frame is read only when the task is a slide (zero otherwise): the frame
    says which edge of a slid body leads, and on other tasks it cost the rope's usual cases ten points."""
    return dataclasses.replace(cpu1k_deformable_frame(), name="cpu1k_deformable_slide_frame",
                               deformable_frame_slides_only=True)  # fmt: skip


__all__ = ["LevelConfig", "NetworkConfig", "config_with_defaults", "get_config", "list_configs", "register_config"]
