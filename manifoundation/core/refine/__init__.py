"""Wrench-based hand pose refinement (paper §III-B): target wrenches, contact forces, the iterative SOCP,
force closure, articulated objects, masked regions, the direct-grasp baseline, verification and evaluation.

Modules: `wrench` (Eq. 4-5, P^J), `grasp` (G_i, cones), `forces` (Eq. 6-8, native Clarabel + CVXPY reference),
`closure` (Ferrari–Canny ε), `field` (point-cloud Φ, Φ^R), `state` (iterate, local model), `step` (Eq. 9-16, native
+ CVXPY reference), `refine` (the loop), `strategy` (approach alignment + restarts), `initialise` (§III-B-1),
`baseline` (direct grasp), `verify` (docs/evaluation.md), `evaluation` (Table II protocol).
"""

from manifoundation.core.errors import Cancelled
from manifoundation.core.refine.closure import ferrari_canny
from manifoundation.core.refine.field import PointCloudField
from manifoundation.core.refine.forces import ForceSolution, solve_forces, solve_forces_cvxpy
from manifoundation.core.refine.initialise import InitCandidate, initialise
from manifoundation.core.refine.refine import RefineConfig, RefineResult, refine
from manifoundation.core.refine.state import HandPose
from manifoundation.core.refine.strategy import refine_from_start
from manifoundation.core.refine.verify import Verification, verify
from manifoundation.core.refine.wrench import WrenchTask, articulated_task, closure_task, rigid_task

__all__ = [
    "Cancelled",
    "ForceSolution",
    "HandPose",
    "InitCandidate",
    "PointCloudField",
    "RefineConfig",
    "RefineResult",
    "Verification",
    "WrenchTask",
    "articulated_task",
    "closure_task",
    "ferrari_canny",
    "initialise",
    "refine",
    "refine_from_start",
    "rigid_task",
    "solve_forces",
    "solve_forces_cvxpy",
    "verify",
]
