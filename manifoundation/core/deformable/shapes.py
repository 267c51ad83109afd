"""One entry point for every deformable shape: `make_body(material, kind, seed)` and the kinds per material."""

from __future__ import annotations

from manifoundation.core.deformable.body import DeformableBody
from manifoundation.core.deformable.cloth import CLOTH_KINDS, make_cloth
from manifoundation.core.deformable.materials import check_material
from manifoundation.core.deformable.plasticine import PLASTICINE_KINDS, make_plasticine
from manifoundation.core.deformable.rope import ROPE_KINDS, make_rope

KINDS: dict[str, tuple[str, ...]] = {"cloth": CLOTH_KINDS, "rope": ROPE_KINDS, "plasticine": PLASTICINE_KINDS}


def make_body(material: str, kind: str, seed: int, properties: dict[str, float] | None = None) -> DeformableBody:
    """A body of ``material`` and shape ``kind`` (one of ``KINDS[material]``), drawn with ``seed``.

    Properties default to a draw inside `materials.RANGES`.
    """
    if kind not in KINDS[check_material(material)]:
        raise ValueError(f"kind: {kind!r} is not a {material} shape ({', '.join(KINDS[material])})")
    if material == "cloth":
        return make_cloth(kind, seed, properties)
    if material == "rope":
        return make_rope(seed, properties)
    return make_plasticine(kind, seed, properties)
