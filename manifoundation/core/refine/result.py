"""What a refinement returns: its result and, when asked, a record per iteration."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from manifoundation.core.refine.state import HandPose


@dataclass
class IterationRecord:
    """One iteration: merit and its parts at the iterate, the trust scale used and whether the step was kept."""

    iteration: int
    residual_norm: float
    max_tip_distance: float
    penetration: float
    self_overlap: float
    merit: float
    trust_scale: float
    accepted: bool
    seconds: float


@dataclass
class RefineResult:
    """Outcome of one refinement.

    Attributes:
        pose: final hand pose (the best iterate).
        forces: (m, 3) world-frame fingertip forces at ``pose``.
        tips, contacts: (m, 3) the contacts: each fingertip's contact sample projected onto the object (the
            linearisation's ``tips``: projecting them again changed nothing but cost a query); normals: (m, 3).
        residual_norm: ‖r*‖; max_tip_distance: max |Φ(p_i)| (Φ^R with a mask); penetration, self_overlap:
            largest sphere violations (m).
        converged: the convergence test passed. reason: "converged", "max_iterations", "stalled",
            "deadline" or "solver_failed: ...".
        iterations: steps attempted. seconds: wall time. history: records when asked for.
    """

    pose: HandPose
    forces: np.ndarray
    tips: np.ndarray
    contacts: np.ndarray
    normals: np.ndarray
    residual_norm: float
    max_tip_distance: float
    penetration: float
    self_overlap: float
    converged: bool
    reason: str
    iterations: int
    seconds: float
    history: list[IterationRecord] = field(default_factory=list)
