"""The ceiling of "contacts + refinement": a predictor that answers with the test case's own valid grasps.

`mani-lab eval network` compares network + refinement with random contacts + refinement. Whether *any* contact
proposal can beat random contacts by the issue's margin depends on what the refinement does with a good start, so
the table carries a third row: the heatmaps of the grasps that are known to produce the case's motion (the grasp
set of `research.data.grasp_sets`, sample k = grasp k mod G, inside a partial mask only the grasps in it), through
the same selection, initialisation, restarts and verification as the network's. It is what a perfect network
would output, so a network row can reach it at best; where it does not beat random contacts either, the margin
is the refinement's, not the network's.
"""

from __future__ import annotations

import hashlib
from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from research.data.grasp_sets import grasps_in_mask, set_maps

if TYPE_CHECKING:
    from manifoundation.core.network.inference import NetworkInput, NetworkOutput
    from research.evaluation.testset import TestCase


def _key(points: np.ndarray) -> str:
    return hashlib.blake2b(np.ascontiguousarray(points, dtype=np.float64).tobytes(), digest_size=16).hexdigest()


class OraclePredictor:
    """``predict`` like `manifoundation.core.network.ContactPredictor`, from the cases' grasp sets (not a network).

    Args:
        cases: the test cases; each needs ``grasp_contacts``, ``grasp_normals`` and ``grasp_forces`` (G, C, 3).
    """

    def __init__(self, cases: Sequence[TestCase]) -> None:
        self._maps: dict[str, tuple[np.ndarray, np.ndarray]] = {}
        for case in cases:
            self._maps.setdefault(_key(case.points) + _key(case.motion), self.case_maps(case))

    @staticmethod
    def case_maps(case: TestCase) -> tuple[np.ndarray, np.ndarray]:
        """Heatmaps (G, N) and force maps (G, N, 3) of the case's valid grasps (inside its mask)."""
        if case.grasp_contacts is None or case.grasp_normals is None or case.grasp_forces is None:
            raise ValueError(f"case {case.object_id}: no grasp set loaded")
        count = len(case.grasp_contacts)
        usable = np.ones(count, dtype=bool)
        if not case.mask.all():
            usable = grasps_in_mask(case.points, case.mask, case.grasp_contacts, count)
        scale = float(np.ptp(case.points, axis=0).max())
        return set_maps(case.points, case.normals, case.grasp_contacts[usable], case.grasp_normals[usable],
                        case.grasp_forces[usable], scale)  # fmt: skip

    def predict(self, batch: Sequence[NetworkInput], num_samples: int = 4, seed: int | Sequence[int] = 0
                ) -> list[NetworkOutput]:  # fmt: skip
        """Sample k of each input is its case's valid grasp k mod G (``seed`` is not used: nothing is drawn)."""
        from manifoundation.core.network.inference import NetworkOutput

        out = []
        for inp in batch:
            key = _key(inp.points) + _key(inp.motion)
            if key not in self._maps:
                raise KeyError("OraclePredictor: an input that is not one of its cases")
            heat, force = self._maps[key]
            pick = np.arange(num_samples) % len(heat)
            out.append(NetworkOutput(heat[pick].astype(np.float32), force[pick].astype(np.float32)))
        return out
