"""Does a converted answer put DGB's hand where ours was? Forward kinematics on both sides, compared.

Ours: the hand as our physics test builds it (`manifoundation.core.physics.hand_model.add_hand`, the palm at the
answer's pose, the grasp's joints). DGB's: its hand XML's body positions for the converted joint values (from the
driver's ``--fk``, in the XML's world frame) placed at the converted root pose. Compared at the bodies that
`research.evaluation.dexgraspbench.DgbHand.bodies` pairs (joint frames: the same points of the hand when both models
agree).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import mujoco
import numpy as np

from research.evaluation.dexgraspbench import _matrix, dgb_hand

if TYPE_CHECKING:
    from manifoundation.core.robots.hand import Hand


def our_bodies(
    hand: Hand, palm_position: np.ndarray, palm_quaternion: np.ndarray, q: np.ndarray
) -> dict[str, np.ndarray]:
    """Our link -> (3,) position of its body in our physics model, for the links `DgbHand.bodies` names."""
    from manifoundation.core.physics import Protocol
    from manifoundation.core.physics.hand_model import add_hand
    from manifoundation.core.physics.visual import physics_description

    spec = mujoco.MjSpec()
    spec.compiler.degree = False
    hm = add_hand(spec, physics_description(hand), list(hand.joint_names), np.asarray(palm_position, float),
                  np.asarray(palm_quaternion, float), Protocol())  # fmt: skip
    model = spec.compile()
    data = mujoco.MjData(model)
    for name, value in hm.joint_values(np.asarray(q, float)).items():
        data.qpos[model.jnt_qposadr[model.joint(name).id]] = value
    mujoco.mj_kinematics(model, data)
    return {link: data.xpos[model.body(hm.link_body[link]).id].copy() for link in dgb_hand(hand.name).bodies}


def dgb_bodies(hand_name: str, root: np.ndarray, xml_world: dict[str, list[float]]) -> dict[str, np.ndarray]:
    """Our link -> (3,) position of its paired DGB body: ``xml_world`` (DGB body -> position in the hand XML's world
    frame, the driver's ``--fk``) placed at the root pose (7,)."""
    R, t = _matrix(np.asarray(root[3:], float)), np.asarray(root[:3], float)
    return {link: R @ np.asarray(xml_world[body]) + t for link, body in dgb_hand(hand_name).bodies.items()}


def max_distance(a: dict[str, np.ndarray], b: dict[str, np.ndarray]) -> float:
    """Largest distance (m) between the paired positions."""
    return max(float(np.linalg.norm(a[k] - b[k])) for k in a)
