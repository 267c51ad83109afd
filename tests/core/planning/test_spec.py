import json

import numpy as np
import pytest
import yaml

from manifoundation.core.planning import BoxObstacle, InvalidPlan, MeshObstacle, PointCloudObstacle
from manifoundation.core.planning.spec import load_plan_file, plan_from_dict
from manifoundation.core.robots import get_hand


def _plan(block, tmp_path):
    mesh, pts, nrm = block
    np.savez(tmp_path / "block.npz", points=pts, normals=nrm, vertices=mesh.vertices, faces=mesh.faces)
    mesh.export(tmp_path / "crate.stl")
    return {
        "object": {"file": "block.npz", "properties": {"friction": 0.8}},
        "robot": {"name": "allegro"},
        "start": {"position": [-0.15, 0, 0.1]},
        "waypoints": [{"position": [0.15, 0, 0.1], "quaternion": [2, 0, 0, 0]}],
        "scene": {"support_plane": {"height": 0.0}, "obstacles": [
            {"kind": "box", "name": "wall", "size": [0.02, 0.4, 0.3], "pose": {"position": [0, 0, 0.15]}},
            {"kind": "mesh", "name": "crate", "file": "crate.stl", "pose": {"position": [0.5, 0.5, 0.0]}},
            {"kind": "points", "points": [[1, 1, 1], [1.01, 1, 1]], "resolution": 0.02},
        ]},
        "options": {"time_limit": 2, "seed": 4, "contacts": False},
    }  # fmt: skip


def test_yaml_and_json_files_load_the_same_request(block, tmp_path):
    data = _plan(block, tmp_path)
    (tmp_path / "plan.yaml").write_text(yaml.safe_dump(data))
    (tmp_path / "plan.json").write_text(json.dumps(data))
    a = load_plan_file(tmp_path / "plan.yaml", get_hand)
    b = load_plan_file(tmp_path / "plan.json", get_hand)
    for inp in (a, b):
        assert inp.hand.name == "allegro" and inp.properties == {"friction": 0.8}
        assert [type(o) for o in inp.obstacles] == [BoxObstacle, MeshObstacle, PointCloudObstacle]
        assert inp.options.seed == 4 and inp.options.time_limit == 2.0 and not inp.options.contacts
        np.testing.assert_allclose(inp.waypoints[0].quaternion, [1, 0, 0, 0])  # normalised, as on the wire
        assert inp.mesh_faces is not None and inp.points.shape == (512, 3)


@pytest.mark.parametrize(
    ("change", "field"),
    [
        (lambda d: d.pop("start"), "plan: missing field(s) start"),
        (lambda d: d["options"].update(speed=3), "options: unknown field(s) speed"),
        (lambda d: d["options"].update(contacts="yes"), "options.contacts: expected true or false"),
        (lambda d: d["scene"]["obstacles"].append({"kind": "cone"}), "scene.obstacles[3].kind"),
        (lambda d: d["robot"].update(name="octopus"), "robot.name"),
        (lambda d: d["waypoints"][0].pop("position"), "waypoints[0]: missing field(s) position"),
        (lambda d: d["object"].update(file="nothing.npz"), "object.file"),
    ],
)
def test_bad_files_name_the_field(block, tmp_path, change, field):
    data = _plan(block, tmp_path)
    change(data)
    with pytest.raises(InvalidPlan) as err:
        plan_from_dict(data, tmp_path, get_hand)
    assert str(err.value).startswith(field)
