"""The simulated grasp test (MuJoCo), the field's meaning of "verified" (DexGraspBench / BODex protocol).

Independent of the optimiser: it reads the hand's description and real meshes (`visual`), builds its own MuJoCo
model (`hand_model`, `object_model`, `scene`) and runs the six-direction test (`trial`, settings in `protocol`).
"""

from manifoundation.core.physics.motion import simulate_motion
from manifoundation.core.physics.object_model import ObjectShape, from_mesh, from_points
from manifoundation.core.physics.protocol import (
    MotionTrial,
    PhysicsResult,
    Protocol,
    Trial,
    physics_order,
)
from manifoundation.core.physics.scene import SceneCache
from manifoundation.core.physics.trial import simulate_grasp

__all__ = [
    "MotionTrial",
    "ObjectShape",
    "PhysicsResult",
    "Protocol",
    "SceneCache",
    "Trial",
    "from_mesh",
    "from_points",
    "physics_order",
    "simulate_grasp",
    "simulate_motion",
]
