"""One MuJoCo scene of the test: the protocol's options, the hand welded at the answer's palm pose, the object."""

from __future__ import annotations

import functools
import threading
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

import mujoco
import numpy as np

from manifoundation.core.physics.hand_model import PREFIX, HandModel, add_hand, overlapping_at_rest
from manifoundation.core.physics.object_model import OBJECT, ObjectShape, add_object
from manifoundation.core.physics.protocol import Protocol
from manifoundation.core.physics.visual import physics_description

if TYPE_CHECKING:
    from manifoundation.core.robots.hand import Hand


PALM_TARGET = "palm_target"
"""The mocap body the free palm is welded to in the target-motion trial."""
PALM_MASS = 1.0
"""The palm's mass in the target-motion trial, kg: a real hand's order, so the weld carries the object stiffly."""


@dataclass
class Scene:
    """The compiled model and the indices the test needs.

    Attributes:
        hand_qpos: (n,) qpos address of each moving hand joint, in ``hand.joints`` order.
        hand_dof: (n,) its dof address. object_qpos: the object's free-joint qpos address (7 values).
        object_body: its body id; hand_bodies: ids of the hand's bodies.
    """

    model: mujoco.MjModel
    data: mujoco.MjData
    hand: HandModel
    hand_qpos: np.ndarray
    hand_dof: np.ndarray
    object_qpos: int
    object_body: int
    hand_bodies: np.ndarray

    def set_joints(self, q: np.ndarray) -> None:
        """Every hand joint from the free joint values q (D,)."""
        values = self.hand.joint_values(q)
        for (name, *_), adr in zip(self.hand.joints, self.hand_qpos, strict=True):
            self.data.qpos[adr] = values[name]

    def place_palm(self, palm_position: np.ndarray, palm_quaternion: np.ndarray) -> None:
        """Move the (fixed) palm to a new pose (3,), (4,) wxyz in the compiled model, as compiling with that pose
        would place it (the quaternion normalised as MuJoCo's compiler does), with fresh data and MuJoCo's default
        solver, Newton, as `build_scene` leaves it (a trial may have switched it to `trial.FALLBACK_SOLVER`). Closure
        scenes only (not ``moving``), whose compiler placed the palm's inertial frame at its body frame (`SceneCache`
        checks)."""
        palm = int(self.hand_bodies[0])
        quat = np.array(palm_quaternion, dtype=np.float64)
        mujoco.mju_normalize4(quat)
        self.model.body_pos[palm] = np.asarray(palm_position, dtype=np.float64)
        self.model.body_quat[palm] = quat
        # MuJoCo's compiler gives the palm, a body welded to the world, the same inertial pose as its body pose; its
        # com-based kinematics of the fingers read it, so a re-posed palm carries it too (bit-identical verdicts)
        self.model.body_ipos[palm] = self.model.body_pos[palm]
        self.model.body_iquat[palm] = quat
        self.model.opt.solver = mujoco.mjtSolver.mjSOL_NEWTON
        self.data = mujoco.MjData(self.model)
        mujoco.mj_setConst(self.model, self.data)  # what the compiler derives at this pose (the solver's weights)

    def coupling(self) -> np.ndarray:
        """(nv, D): d qvel / d q̇_free (the mimic multipliers)."""
        C = np.zeros((self.model.nv, len(self.hand.free_joints)))
        for (_, src, mult, _), dof in zip(self.hand.joints, self.hand_dof, strict=True):
            C[dof, src] = mult
        return C


@functools.lru_cache(maxsize=32)
def _rest_overlaps(hand: Hand) -> frozenset[tuple[str, str]]:
    return frozenset(overlapping_at_rest(physics_description(hand), list(hand.joint_names), hand.rest))


_COPYING = threading.Lock()


@functools.lru_cache(maxsize=32)
def _hand_spec(hand: Hand, protocol: Protocol) -> tuple[mujoco.MjSpec, HandModel]:
    """The protocol's options and the hand (its palm at the origin), built once per hand and protocol: a scene is a
    copy with the palm placed and the object added (building the hand's bodies and 103 meshes anew cost LEAP 9 ms
    a scene; the compiled model is the same, `tests/core/physics/test_scene_spec.py`). Never edited after."""
    spec = mujoco.MjSpec()
    spec.compiler.degree = False  # joint ranges in radians (MJCF's default is degrees)
    opt = spec.option
    opt.timestep = protocol.timestep
    opt.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    opt.disableflags = int(mujoco.mjtDisableBit.mjDSBL_GRAVITY)
    opt.cone = mujoco.mjtCone.mjCONE_ELLIPTIC
    opt.impratio = protocol.impratio
    opt.noslip_iterations = 2
    hm = add_hand(spec, physics_description(hand), list(hand.joint_names), np.zeros(3), np.array([1.0, 0, 0, 0]),
                  protocol, _rest_overlaps(hand))  # fmt: skip
    return spec, hm


def build_scene(
    hand: Hand, palm_position: np.ndarray, palm_quaternion: np.ndarray, shape: ObjectShape, protocol: Protocol,
    moving: bool = False,
) -> Scene:
    """Compile the scene (palm pose wxyz in the world frame; the object's pieces in the world frame).

    ``moving`` (the target-motion trial): the palm gets a free joint welded to the mocap body ``palm_target``
    (driven through ``data.mocap_pos`` / ``mocap_quat``) and the hand's bodies are gravity-compensated."""
    base, hm = _hand_spec(hand, protocol)
    with _COPYING:
        spec = base.copy()
    palm = spec.body(hm.bodies[0])
    palm.pos, palm.quat = np.asarray(palm_position, float), np.asarray(palm_quaternion, float)
    if moving:  # a free palm welded to a mocap body, as DexGraspBench's base (see `motion`)
        palm.add_freejoint(name=PREFIX + "palm/free")
        palm.mass = PALM_MASS
        target = spec.worldbody.add_body(name=PALM_TARGET, pos=palm.pos, quat=palm.quat, mocap=True)
        weld = spec.add_equality(type=mujoco.mjtEq.mjEQ_WELD, objtype=mujoco.mjtObj.mjOBJ_BODY)
        weld.name1, weld.name2 = target.name, palm.name
        weld.solref = [2 * protocol.timestep, 1.0]
        weld.data = [0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 1, 0]  # anchor, relative pose (identity), torque scale
        for b in hm.bodies:
            spec.body(b).gravcomp = 1.0
    add_object(spec, shape, protocol)
    for g in spec.geoms:
        g.friction = [protocol.friction[0], protocol.friction[1], 0.0001]
        g.condim = 4
    model = spec.compile()
    data = mujoco.MjData(model)
    qadr = np.array([model.jnt_qposadr[model.joint(name).id] for name, *_ in hm.joints], dtype=np.int64)
    dadr = np.array([model.jnt_dofadr[model.joint(name).id] for name, *_ in hm.joints], dtype=np.int64)
    obj_joint = model.joint(OBJECT + "/free").id
    bodies = np.array([model.body(b).id for b in hm.bodies], dtype=np.int64)
    assert all(model.body(int(b)).name.startswith(PREFIX) for b in bodies)
    return Scene(model, data, hm, qadr, dadr, int(model.jnt_qposadr[obj_joint]), int(model.body(OBJECT).id), bodies)


class SceneCache:
    """The closure scenes of one object, compiled once per hand and protocol and re-posed for each grasp
    (`Scene.place_palm`): compiling costs 0.29 s for LEAP's 103 convex pieces, a request's search tests up to 16
    grasps of one object, and the palm is a fixed body, so a re-posed scene holds the same numbers as a new one
    (the verdicts are bit-identical: tests/core/physics)."""

    def __init__(self, shape: ObjectShape) -> None:
        self.shape = shape
        self._scenes: dict[tuple[Hand, Protocol], Scene] = {}

    def scene(self, hand: Hand, palm_position: np.ndarray, palm_quaternion: np.ndarray, protocol: Protocol) -> Scene:
        """The scene of ``hand`` at this palm pose (wxyz) with ``protocol``'s physics."""
        key = (hand, replace(protocol, stop_at_first_failure=False))  # the one setting that is not the model's
        sc = self._scenes.get(key)
        if sc is None:
            sc = build_scene(hand, palm_position, palm_quaternion, self.shape, protocol)
            m, palm = sc.model, int(sc.hand_bodies[0])
            inertial_at_body = np.array_equal(m.body_ipos[palm], m.body_pos[palm]) and np.array_equal(
                m.body_iquat[palm], m.body_quat[palm])  # fmt: skip
            if inertial_at_body:
                self._scenes[key] = sc  # else (another MuJoCo's compiler) every grasp is compiled anew
        else:
            sc.place_palm(palm_position, palm_quaternion)
        return sc
