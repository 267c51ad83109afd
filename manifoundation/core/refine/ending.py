"""How a refinement attempt ends before its budget: converged (on the mesh's contacts too), or verified.

Two tests stand beside the SCP's own convergence test (`manifoundation.core.refine.refine`):

- where the request sent the object's mesh, a convergence must also hold on the mesh's contacts
  (`mesh_agrees`): the refinement's contacts are projected on the points' surface, and near an edge the
  projection and the mesh's closest point can lie on different faces whose normals differ (26 of 27
  converged-but-unverified LEAP and Allegro lifts on 258 third-party requests failed on the wrench). When it does
  not hold, the attempt goes on with its contacts on the mesh (``exact``).
- the SCP's test asks every fingertip within 2 mm of the points' surface; verification asks 4 mm on the exact
  geometry. Once an iterate meets the SCP's test with a looser tip tolerance, the caller's ``accept`` (the
  pipeline's verification) is asked, and again only after the farthest tip came ``recheck`` nearer: a pose it
  accepts ends the attempt ("verified"). On 258 third-party lifts the converged attempts spent 19-28 % of their
  iterations after the first iterate within 5 mm.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from manifoundation.core.refine.contact import ObjectField
from manifoundation.core.refine.forces import solve_forces
from manifoundation.core.refine.state import HandPose, Linearisation
from manifoundation.core.refine.verify import produces_wrench


def mesh_agrees(lin: Linearisation, field_: ObjectField) -> bool:
    """Whether the contacts on the object's mesh — the closest points to the contact samples, with the caller's
    normals there: what verification measures — produce the task's wrench within verification's tolerance; True
    where the field has no mesh (``field_.exact``)."""
    surface = getattr(field_, "exact", None)
    if surface is None or lin.samples is None:
        return True
    on = surface.closest(lin.samples)[0]
    sol = solve_forces(lin.task, on, field_.given_normal(on), lin.mu, lin.max_normal_force)
    return produces_wrench(sol)


@dataclass
class Endings:
    """The early endings of one attempt (module doc).

    Attributes:
        field_: the object (its ``exact`` mesh surface, if any).
        converged: the SCP's convergence test of an iterate.
        nearly: the same test with a looser tip tolerance (when ``accept`` is asked).
        accept: verification of a pose (None: never asked).
        recheck: how much nearer (m) the farthest tip must come before ``accept`` is asked again.
        exact: the contacts are on the mesh (set at the first convergence the mesh contradicts).
    """

    field_: ObjectField
    converged: Callable[[Linearisation], bool]
    nearly: Callable[[Linearisation], bool]
    accept: Callable[[HandPose], bool] | None = None
    recheck: float = 1e-3
    exact: bool = False
    _ask_below: float = np.inf

    def at(self, lin: Linearisation, pose: HandPose) -> str:
        """At an iterate: "converged", "verified", "exact" (just switched to the mesh's contacts: linearise
        again), or "" (go on)."""
        if self.converged(lin):
            if self.exact or mesh_agrees(lin, self.field_):
                return "converged"
            self.exact = True
            return "exact"
        if self.accept is not None and self.nearly(lin):
            farthest = float(np.max(np.abs(lin.tip_phi)))
            if farthest < self._ask_below:
                if self.accept(pose):
                    return "verified"
                self._ask_below = farthest - self.recheck
        return ""

    def final(self, reason: str, lin: Linearisation) -> str:
        """The reason of an attempt whose loop ended with ``reason``: "converged" when its last iterate
        converged (and the mesh agrees)."""
        if reason in ("converged", "verified") or reason.startswith("solver_failed") or not self.converged(lin):
            return reason
        return "converged" if self.exact or mesh_agrees(lin, self.field_) else reason
