"""Inference API: plain arrays in, :class:`NetworkOutput` out, in the request's frame and units.

``ContactPredictor.predict(batch, num_samples=K, seed=s)`` normalises each object (normalize.py), resamples
it to the model's point count (resample.py: FPS down, or repeat up; outputs are mapped back to the request's
N points), encodes the batch once, draws K latent samples per object from N(0, s² I) and decodes them all, with
s the weights' ``prior_scale`` (their model card; 1 for weights that name none).

- Hands: ε^h is cached per ``hand_key`` (with a fingerprint of the arrays, so a changed hand under the same
  key is re-encoded rather than silently reused).
- Determinism: an object's output depends only on (object, hand, ``seed``, K): its z comes from its own
  generator seeded with its seed, and sampling/grouping are deterministic, so batch-mates do not matter.
"""

from __future__ import annotations

import hashlib
from collections import OrderedDict
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import torch

from manifoundation.core.network.checkpoint import ModelCard, checked_prior_scale, load_checkpoint
from manifoundation.core.network.config import NetworkConfig
from manifoundation.core.network.model import ManiFoundationNet, ObjectTensors, create_model
from manifoundation.core.network.normalize import Normalizer
from manifoundation.core.network.properties import property_tensors
from manifoundation.core.network.resample import Resampling, resample
from manifoundation.core.network.validation import validate_input

MAX_DECODE_ROWS = 32  # (object, sample) pairs decoded at once; bounds peak memory for large batches


@dataclass
class NetworkInput:
    """One object, task and hand, in the request's frame (metres).

    Attributes:
        points: (N, 3) object points.
        normals: (N, 3) unit outward normals.
        motion: (N, 3) target per-point motion (displacement).
        mask: (N,) bool region mask, True = contact allowed.
        properties: physical properties keyed by ``PROPERTY_NAMES`` (missing ones are masked).
        hand_points: (M_h, 3) hand surface points in its palm frame.
        hand_normals: (M_h, 3) their unit normals.
        hand_key: identifies the hand for caching its encoding (e.g. the built-in hand's name).
    """

    points: np.ndarray
    normals: np.ndarray
    motion: np.ndarray
    mask: np.ndarray
    properties: dict[str, float]
    hand_points: np.ndarray
    hand_normals: np.ndarray
    hand_key: str


@dataclass
class NetworkOutput:
    """K latent samples for one object, on the request's N points.

    Attributes:
        heatmaps: (K, N) contact heatmaps in [0, 1] (as predicted: the region mask is enforced at selection).
        force_maps: (K, N, 3) force/motion maps in the request's frame and units.
    """

    heatmaps: np.ndarray
    force_maps: np.ndarray


@dataclass
class _HandCache:
    size: int
    entries: OrderedDict[str, tuple[str, torch.Tensor]] = field(default_factory=OrderedDict)
    hits: int = 0
    misses: int = 0


def _fingerprint(points: np.ndarray, normals: np.ndarray) -> str:
    h = hashlib.blake2b(digest_size=16)
    for a in (points, normals):
        arr = np.ascontiguousarray(a, dtype=np.float32)
        h.update(str(arr.shape).encode())
        h.update(arr.tobytes())
    return h.hexdigest()


class ContactPredictor:
    """Runs the network for batches of :class:`NetworkInput`.

    Build it with :meth:`from_checkpoint` (trained weights) or :meth:`untrained` (random weights, for tests
    and benchmarks; ``is_trained`` is False and the card says so).
    """

    def __init__(
        self, model: ManiFoundationNet, card: ModelCard, device: str | torch.device = "cpu", hand_cache_size: int = 64
    ) -> None:
        self.model = model.to(device).eval()
        self.card = card
        self.device = torch.device(device)
        self.prior_scale = card.prior_scale
        self._hands = _HandCache(hand_cache_size)

    @classmethod
    def from_checkpoint(
        cls, path: str | Path, config: str | NetworkConfig | None = None, device: str | torch.device = "cpu"
    ) -> ContactPredictor:
        """Load a checkpoint directory (see checkpoint.py); ``config`` is the configuration expected."""
        model, card = load_checkpoint(path, config)
        return cls(model, card, device)

    @classmethod
    def untrained(
        cls, config: str | NetworkConfig = "cpu", seed: int = 0, device: str | torch.device = "cpu"
    ) -> ContactPredictor:
        """Randomly initialised weights (seeded). Its outputs are meaningless; for tests and benchmarks only."""
        model = create_model(config, seed=seed)
        card = ModelCard.for_model(model, trained=False, notes=f"untrained, random init with seed {seed}")
        return cls(model, card, device)

    @property
    def prior_scale(self) -> float:
        """The latent samples' standard deviation s, z ~ N(0, s² I) (the card's; settable, a finite number ≥ 0)."""
        return self._prior_scale

    @prior_scale.setter
    def prior_scale(self, value: float) -> None:
        self._prior_scale = checked_prior_scale(value)

    @property
    def is_trained(self) -> bool:
        """Whether the weights come from training (False for :meth:`untrained`)."""
        return self.card.trained

    @property
    def config(self) -> NetworkConfig:
        return self.model.config

    def hand_cache_info(self) -> dict[str, int]:
        """Hits, misses and current size of the hand-encoding cache."""
        c = self._hands
        return {"hits": c.hits, "misses": c.misses, "size": len(c.entries)}

    @torch.inference_mode()
    def _hand_features(self, batch: Sequence[NetworkInput]) -> torch.Tensor:
        cache, rows = self._hands, []
        for inp in batch:
            fp = _fingerprint(inp.hand_points, inp.hand_normals)
            hit = cache.entries.get(inp.hand_key)
            if hit is not None and hit[0] == fp:
                cache.hits += 1
                cache.entries.move_to_end(inp.hand_key)
                rows.append(hit[1])
                continue
            cache.misses += 1
            hand = np.concatenate([inp.hand_points / self.config.hand_scale_m, inp.hand_normals], axis=1)
            t = torch.as_tensor(hand, dtype=torch.float32, device=self.device).unsqueeze(0)
            feat = self.model.encode_hand(t)[0]
            cache.entries[inp.hand_key] = (fp, feat)
            while len(cache.entries) > cache.size:
                cache.entries.popitem(last=False)
            rows.append(feat)
        return torch.stack(rows)

    @torch.inference_mode()
    def predict(
        self, batch: Sequence[NetworkInput], num_samples: int = 4, seed: int | Sequence[int] = 0
    ) -> list[NetworkOutput]:
        """K heatmap / force-map samples per object.

        Args:
            batch: objects (any N each, same or different hands).
            num_samples: K latent samples per object, sharing one encoder pass.
            seed: one seed for every object, or one per object.

        Returns:
            One :class:`NetworkOutput` per input, in order.

        Raises:
            ValueError: an input with a wrong shape, non-finite values, or unknown properties.
        """
        if not batch:
            return []
        if num_samples < 1:
            raise ValueError(f"num_samples must be ≥ 1, got {num_samples}")
        seeds = [seed] * len(batch) if isinstance(seed, int) else list(seed)
        if len(seeds) != len(batch):
            raise ValueError(f"got {len(seeds)} seeds for {len(batch)} inputs")
        for i, inp in enumerate(batch):
            validate_input(inp, where=f"batch[{i}]")
        m = self.config.num_points
        norms = [Normalizer.fit(inp.points) for inp in batch]
        resamplings = [resample(nz.points(inp.points), m) for nz, inp in zip(norms, batch, strict=True)]
        obj = self._object_tensors(batch, norms, resamplings)
        enc = self.model.encode(obj, self._hand_features(batch))
        z = self.prior_scale * torch.stack(
            [
                torch.randn(num_samples, self.config.latent_dim, generator=torch.Generator().manual_seed(int(s)))
                for s in seeds
            ]
        ).to(self.device)
        outputs = []
        per_chunk = max(1, MAX_DECODE_ROWS // num_samples)
        for start in range(0, len(batch), per_chunk):
            sl = slice(start, start + per_chunk)
            heat, force = self.model.decode(enc.rows(sl), z[sl])
            heat_np, force_np = heat.float().cpu().numpy(), force.float().cpu().numpy()
            for j in range(heat_np.shape[0]):
                i = start + j
                r, nz = resamplings[i], norms[i]
                outputs.append(
                    NetworkOutput(
                        heatmaps=r.map_back(heat_np[j][..., None])[..., 0].astype(np.float32),
                        force_maps=nz.unvectors(r.map_back(force_np[j])).astype(np.float32),
                    )
                )
        return outputs

    def _object_tensors(
        self, batch: Sequence[NetworkInput], norms: Sequence[Normalizer], resamplings: Sequence[Resampling]
    ) -> ObjectTensors:
        rows: dict[str, list[np.ndarray]] = {"xyz": [], "normals": [], "motion": [], "mask": []}
        for inp, nz, r in zip(batch, norms, resamplings, strict=True):
            idx = r.indices
            rows["xyz"].append(nz.points(inp.points)[idx])
            rows["normals"].append(np.asarray(inp.normals, dtype=np.float64)[idx])
            rows["motion"].append(nz.vectors(inp.motion)[idx])
            rows["mask"].append(np.asarray(inp.mask, dtype=np.float64)[idx])
        values, present = property_tensors([inp.properties for inp in batch])

        def t(key: str) -> torch.Tensor:
            return torch.as_tensor(np.stack(rows[key]), dtype=torch.float32, device=self.device)

        return ObjectTensors(
            xyz=t("xyz"),
            normals=t("normals"),
            motion=t("motion"),
            mask=t("mask"),
            prop_values=values.to(self.device),
            prop_mask=present.to(self.device),
            scale=torch.tensor([nz.scale for nz in norms], dtype=torch.float32, device=self.device),
        )
