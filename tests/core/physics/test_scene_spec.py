"""Scenes are copies of one hand spec per hand and protocol (palm placed, object added): the compiled model is the
one a spec built from scratch with the palm at that pose gives, to the bit, whichever scenes were built before."""

from __future__ import annotations

import mujoco
import numpy as np
import trimesh

from manifoundation.core.physics.hand_model import add_hand
from manifoundation.core.physics.object_model import add_object, from_mesh
from manifoundation.core.physics.protocol import Protocol
from manifoundation.core.physics.scene import _rest_overlaps, build_scene
from manifoundation.core.physics.visual import physics_description
from manifoundation.core.robots.registry import get_hand

FIELDS = ("body_pos", "body_quat", "body_ipos", "body_iquat", "body_mass", "body_inertia", "body_gravcomp",
          "jnt_range", "jnt_axis", "dof_armature", "dof_damping", "geom_pos", "geom_quat", "geom_size",
          "geom_friction", "geom_solref", "geom_solimp", "geom_condim", "mesh_vert", "mesh_graph",
          "actuator_gainprm", "actuator_biasprm", "eq_data", "exclude_signature", "opt.timestep", "opt.impratio",
          "opt.cone", "opt.integrator", "opt.disableflags", "opt.noslip_iterations")  # fmt: skip


def _from_scratch(name: str, pos: np.ndarray, quat: np.ndarray, shape: object, p: Protocol) -> mujoco.MjModel:
    """The scene as built before the shared spec: every option, the hand at the pose and the object in one spec."""
    hand = get_hand(name)
    spec = mujoco.MjSpec()
    spec.compiler.degree = False
    spec.option.timestep = p.timestep
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    spec.option.disableflags = int(mujoco.mjtDisableBit.mjDSBL_GRAVITY)
    spec.option.cone = mujoco.mjtCone.mjCONE_ELLIPTIC
    spec.option.impratio = p.impratio
    spec.option.noslip_iterations = 2
    add_hand(spec, physics_description(hand), list(hand.joint_names), pos, quat, p, _rest_overlaps(hand))
    add_object(spec, shape, p)  # type: ignore[arg-type]
    for g in spec.geoms:
        g.friction = [p.friction[0], p.friction[1], 0.0001]
        g.condim = 4
    return spec.compile()


def _field(model: mujoco.MjModel, name: str) -> np.ndarray:
    obj: object = model
    for part in name.split("."):
        obj = getattr(obj, part)
    return np.asarray(obj)


def test_a_copied_hand_spec_compiles_to_the_model_built_from_scratch() -> None:
    p = Protocol()
    box = trimesh.creation.box((0.05, 0.06, 0.07))
    cyl = trimesh.creation.cylinder(radius=0.03, height=0.1)
    shapes = [from_mesh(np.asarray(m.vertices), np.asarray(m.faces)) for m in (box, cyl)]
    rng = np.random.default_rng(3)
    for name in ("allegro", "leap"):
        for shape in shapes:  # the second scene of a hand is a copy of the same (cached) spec as the first
            pos = rng.normal(scale=0.1, size=3)
            quat = rng.normal(size=4)
            quat /= np.linalg.norm(quat)
            copied = build_scene(get_hand(name), pos, quat, shape, p).model
            scratch = _from_scratch(name, pos, quat, shape, p)
            assert copied.nbody == scratch.nbody and copied.ngeom == scratch.ngeom
            for field in FIELDS:
                assert np.array_equal(_field(copied, field), _field(scratch, field)), (name, field)
