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
