import numpy as np

from manifoundation.core.refine.field import PointCloudField
from manifoundation.core.refine.initialise import initialise
from manifoundation.core.refine.state import linearise
from manifoundation.core.refine.step import StepParams, solve_step, solve_step_cvxpy
from manifoundation.core.refine.wrench import closure_task, rigid_task


def test_native_step_matches_cvxpy_reference(box, gripper):
    _, pts, nrm = box
    field = PointCloudField(pts, nrm)
    start = initialise(gripper, field, np.array([[0.02, 0.01, 0], [-0.02, 0, 0]]), np.array([[1.0, 0, 0], [-1, 0, 0]]))
    base = np.concatenate([np.full(3, 0.01), np.full(3, 0.1), np.full(gripper.dof, 0.15)])
    for task in (closure_task(np.zeros(3), 0.05), rigid_task(np.array([0, 0, 1.0, 0, 0.2, 0]), np.zeros(3), 0.05)):
        lin = linearise(gripper, start[0].pose, field, task, 0.5, 1.0)
        a = solve_step(lin, StepParams(base, 0.25))
        b = solve_step_cvxpy(lin, StepParams(base, 0.25))
        assert a.delta is not None and b.delta is not None
        assert abs(a.objective - b.objective) < 1e-6 * max(1.0, abs(b.objective))
        # the minimiser need not be unique (e.g. a roll about the jaw axis); the optimal value is
        assert np.all(np.abs(a.delta) <= base + 1e-7)
