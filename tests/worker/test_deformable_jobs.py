"""Deformable requests through the worker's pipeline: wire request → contacts with post-contact motions."""

from __future__ import annotations

import numpy as np
import pytest
from pydantic import ValidationError

from manifoundation.contract import SynthesisRequest
from manifoundation.core.deformable.rope import make_rope


def _rope_request(task: dict[str, object], method: str = "network") -> SynthesisRequest:
    rope = make_rope(seed=0)
    return SynthesisRequest.model_validate({
        "object": {"points": rope.points, "normals": rope.normals, "material": "rope",
                   "properties": {"friction": 0.6, "youngs_modulus": 1e6, "poisson_ratio": 0.3}},
        "task": task, "robot": {"name": "panda_gripper"}, "options": {"method": method, "num_proposals": 2},
    })  # fmt: skip


def test_shipped_network_answers_a_rope_drag_with_contacts_and_motions() -> None:
    from manifoundation.server.worker.models_pipeline import ModelsPipeline
    from manifoundation.server.worker.pipeline import JobInput

    pipeline = ModelsPipeline(hands=["panda_gripper"])
    motion = np.zeros((len(make_rope(seed=0).points), 3))
    motion[:10] = [0.05, 0.0, 0.0]
    request = _rope_request({"kind": "point_motion", "motion": motion})
    [result] = pipeline.run([JobInput(id="rope", request=request)], lambda *a: None, lambda job_id: False)
    assert not hasattr(result, "error"), result
    for proposal in result.proposals:  # type: ignore[union-attr]
        assert proposal.contact_motions is not None
        assert proposal.contact_motions.shape == proposal.contact_points.shape
        assert len(proposal.fingertips) == len(proposal.contact_points)
        assert proposal.contact_source in ("network", "motion_fallback")


def test_unordered_targets_may_differ_in_count_but_ordered_ones_may_not() -> None:
    targets = np.zeros((190, 3)) + np.linspace(0, 1, 190)[:, None]
    assert _rope_request({"kind": "target_points", "targets": targets, "correspondence": "unknown"})
    with pytest.raises(ValidationError, match="targets"):
        _rope_request({"kind": "target_points", "targets": targets})


def test_yield_stress_is_a_plasticine_property_only() -> None:
    rope = make_rope(seed=0)
    body = {"object": {"points": rope.points, "material": "plasticine", "properties": {"yield_stress": 2e4}},
            "task": {"kind": "force_closure"}, "robot": {"name": "leap"}}  # fmt: skip
    assert SynthesisRequest.model_validate(body).object.properties.present()["yield_stress"] == 2e4
    body["object"]["material"] = "rope"  # type: ignore[index]
    with pytest.raises(ValidationError, match="yield_stress not meaningful"):
        SynthesisRequest.model_validate(body)
