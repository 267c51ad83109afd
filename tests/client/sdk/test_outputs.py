"""Results to dict/JSON and back, and the plotly figure of a grasp."""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from manifoundation.sdk import load_result, object_from_points, result_figure, result_to_dict, result_to_json


def test_dict_and_json_round_trip(tmp_path: Path, result_factory: Callable[..., Any]) -> None:
    result = result_factory()
    data = result_to_dict(result)
    assert isinstance(data["proposals"][0]["contact_points"], list)
    text = result_to_json(result, tmp_path / "r.json")
    assert json.loads(text) == data
    back = load_result(tmp_path / "r.json")
    assert np.allclose(back.proposals[0].forces, result.proposals[0].forces)


def test_figure_shows_object_heatmap_contacts_forces_and_palm(
    result_factory: Callable[..., Any], object_points: np.ndarray
) -> None:
    obj = object_from_points(object_points)
    result = result_factory()
    result.heatmap = np.linspace(0, 1, obj.num_points)
    fig = result_figure(result, obj)
    names = [t.name for t in fig.data]
    assert names[:4] == ["object (heatmap)", "contacts", "forces", "force heads"]
    assert {"palm frame", "hand (palm → fingertips)", "palm", "fingertips"} <= set(names)
    assert len(fig.data[0].x) == 256 and fig.data[0].marker.colorscale is not None
    assert len(fig.data[1].x) == 4
    assert "success" in fig.layout.title.text
    bare = result_figure(result_factory(), title="t")
    assert bare.data[0].name == "contacts" and bare.layout.title.text == "t"
    html = fig.to_html(include_plotlyjs=False)
    assert "contacts" in html


def test_the_quality_line_says_whether_it_held_in_physics(result_factory: Callable[..., Any]) -> None:
    from manifoundation.contract import PhysicsQuality, PhysicsTrial
    from manifoundation.sdk.outputs import quality_text

    result = result_factory()
    p = result.proposals[0]
    assert "physics" not in quality_text(p)
    pushes = [PhysicsTrial(direction=d, translation=0.002, rotation=1.0, held=True) for d in ("-x", "+x", "-y")]
    moved = PhysicsTrial(direction="+y", translation=0.046, rotation=81.0, held=False)
    common = {"penetration": 0.0, "touching_after_squeeze": 3, "seconds": 0.2, "object_pieces": "hull"}
    p.quality.physics = PhysicsQuality(held=False, reason="moved", trials=[*pushes, moved], **common)
    assert "physics: moved (push +y: 4.6 cm, 81°)" in quality_text(p)
    p.quality.physics = PhysicsQuality(held=True, reason="held", trials=pushes, **common)
    assert "physics: held (moved ≤ 0.2 cm)" in quality_text(p)
    assert "physics: held" in result_figure(result).layout.title.text
