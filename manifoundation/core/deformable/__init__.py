"""Deformable objects (cloth, rope, plasticine) on MuJoCo 4.0 flex bodies: shapes, simulation, metrics.

`simulate(body, contacts, motions) -> Rollout` is the one physics that data generation and evaluation share;
`shapes.make_body` draws the bodies (`cloth`, `rope`, `plasticine` modules), `materials` maps the contract's
properties to MuJoCo's parameters, `metrics.shape_score` is the paper's success test. Pure: numpy, scipy,
matplotlib (point-in-polygon) and mujoco; nothing from clients, service or workers. See docs/deformables.md.
"""

from manifoundation.core.deformable.body import DeformableBody
from manifoundation.core.deformable.materials import MATERIALS, RANGES
from manifoundation.core.deformable.metrics import ShapeScore, shape_score
from manifoundation.core.deformable.shapes import KINDS, make_body
from manifoundation.core.deformable.simulate import Rollout, SimConfig, simulate

__all__ = [
    "KINDS",
    "MATERIALS",
    "RANGES",
    "DeformableBody",
    "Rollout",
    "ShapeScore",
    "SimConfig",
    "make_body",
    "shape_score",
    "simulate",
]
