"""World poses of a hand's links at one pose, as numpy, computed once for the checks that share the pose."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import torch

if TYPE_CHECKING:
    from manifoundation.core.robots.hand import Hand


def link_poses_at(hand: Hand, palm_pos: np.ndarray, palm_quat: np.ndarray, q: np.ndarray) -> dict[str, np.ndarray]:
    """World pose (4, 4) of every link at one hand pose. The last pose's are kept on the hand: a verification
    asks three times for the same pose (fingertip distances, penetration, self-collision), and forward
    kinematics costs ≈ 1.7 ms a call for LEAP."""
    pos = np.asarray(palm_pos, dtype=np.float64).reshape(3)
    quat = np.asarray(palm_quat, dtype=np.float64).reshape(4)
    joints = np.asarray(q, dtype=np.float64).reshape(hand.dof)
    key = (pos.tobytes(), quat.tobytes(), joints.tobytes())
    last = hand.__dict__.get("_last_link_poses")
    if last is not None and last[0] == key:
        cached: dict[str, np.ndarray] = last[1]
        return cached
    d = torch.float64
    with torch.no_grad():
        poses = hand.link_poses(torch.as_tensor(pos[None], dtype=d), torch.as_tensor(quat[None], dtype=d),
                                torch.as_tensor(joints[None], dtype=d))  # fmt: skip
    out = {k: v[0].numpy() for k, v in poses.items()}
    for pose in out.values():
        pose.flags.writeable = False  # shared by the callers of the same pose
    hand.__dict__["_last_link_poses"] = (key, out)
    return out
