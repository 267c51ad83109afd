"""Object geometry: KD-tree signed distance, mass properties, rigid fits, fcl verification of hand poses."""

from manifoundation.core.errors import InvalidPointCloud
from manifoundation.core.geometry.collision import (
    hand_field_penetration,
    hand_mesh_penetration,
    hand_object_penetration,
    hand_self_collision,
)
from manifoundation.core.geometry.object import DEFAULT_DENSITY, MassProperties, ObjectGeometry
from manifoundation.core.geometry.rigid import RigidFit, fit_rigid_motion, rotation_vector

__all__ = [
    "DEFAULT_DENSITY",
    "InvalidPointCloud",
    "MassProperties",
    "ObjectGeometry",
    "RigidFit",
    "fit_rigid_motion",
    "hand_field_penetration",
    "hand_mesh_penetration",
    "hand_object_penetration",
    "hand_self_collision",
    "rotation_vector",
]
