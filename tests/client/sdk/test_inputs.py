"""Objects from arrays, meshes and files; tasks from poses and target clouds; requests; robot registration."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import trimesh
from hypothesis import given, settings
from hypothesis import strategies as st

from manifoundation.contract import DeltaPoseTask, ForceClosureTask, Material, TargetPointsTask, WrenchTask
from manifoundation.sdk import (
    ValidationError,
    delta_pose,
    force_closure,
    make_request,
    object_from_file,
    object_from_mesh,
    object_from_points,
    robot_registration,
    save_object,
    target_points,
    wrench,
)
from manifoundation.sdk.objects import as_object
from manifoundation.sdk.tasks import as_task, rotation_to_quaternion


def test_points_with_and_without_normals(object_points: np.ndarray) -> None:
    obj = object_from_points(object_points, properties={"friction": 0.7})
    assert obj.points.shape == (256, 3) and obj.normals is not None
    assert np.allclose(np.linalg.norm(obj.normals, axis=1), 1)
    assert obj.properties.friction == 0.7
    assert object_from_points(object_points[:, :3]).normals is None
    with pytest.raises(ValidationError) as info:
        object_from_points(object_points[:10])
    assert info.value.detail[0].field == "object.points"
    bad = object_points.copy()
    bad[5, 0] = np.nan
    with pytest.raises(ValidationError, match="NaN"):
        object_from_points(bad)


def test_mesh_sampling_gives_outward_normals_and_the_mesh() -> None:
    box = trimesh.creation.box(extents=(0.1, 0.06, 0.04))
    obj = object_from_mesh(box, 500, seed=1)
    assert obj.points.shape == (500, 3) and obj.mesh is not None and len(obj.mesh.faces) == 12
    assert np.all(np.einsum("ij,ij->i", obj.points, obj.normals) > 0)  # centred box: normals point away
    assert np.allclose(object_from_mesh(box, 500, seed=1).points, obj.points)  # seeded
    assert object_from_mesh(box, 100, include_mesh=False).mesh is None


@pytest.mark.parametrize("suffix", [".ply", ".obj", ".stl"])
def test_mesh_files(tmp_path: Path, suffix: str) -> None:
    path = tmp_path / f"cyl{suffix}"
    trimesh.creation.cylinder(radius=0.03, height=0.1, sections=24).export(path)
    obj = object_from_file(path, 300, material="rigid")
    assert obj.points.shape == (300, 3) and obj.normals is not None
    assert np.all(np.abs(obj.points[:, 2]) <= 0.05 + 1e-9)
    assert np.mean(np.einsum("ij,ij->i", obj.points, obj.normals) > 0) > 0.99


def test_point_cloud_ply_keeps_its_normals(tmp_path: Path, object_points: np.ndarray) -> None:
    path = tmp_path / "cloud.ply"
    header = ["ply", "format ascii 1.0", f"element vertex {len(object_points)}"]
    header += [f"property float {n}" for n in ("x", "y", "z", "nx", "ny", "nz")] + ["end_header"]
    rows = [" ".join(f"{v:.6f}" for v in row) for row in object_points]
    path.write_text("\n".join(header + rows) + "\n")
    obj = object_from_file(path)
    assert np.allclose(obj.points, object_points[:, :3], atol=1e-6)
    assert obj.normals is not None and np.allclose(obj.normals, object_points[:, 3:], atol=1e-5)


def test_npz_round_trip(tmp_path: Path) -> None:
    mask = np.zeros(200, dtype=bool)
    mask[:50] = True
    box = trimesh.creation.box(extents=(0.1, 0.1, 0.1))
    obj = object_from_mesh(box, 200, region_mask=mask, material=Material.RIGID)
    back = object_from_file(save_object(obj, tmp_path / "box.npz"))
    assert np.array_equal(back.points, obj.points) and np.array_equal(back.region_mask, mask)
    assert back.mesh is not None and np.array_equal(back.mesh.faces, obj.mesh.faces)  # type: ignore[union-attr]
    np.savez(tmp_path / "empty.npz", normals=obj.normals)
    with pytest.raises(ValueError, match="points"):
        object_from_file(tmp_path / "empty.npz")
    with pytest.raises(ValueError, match="unsupported"):
        object_from_file(tmp_path / "x.xyz")


def test_as_object_accepts_every_form(tmp_path: Path, object_points: np.ndarray) -> None:
    obj = object_from_points(object_points)
    assert as_object(obj) is obj
    assert as_object(obj, properties={"friction": 0.9}).properties.friction == 0.9
    with pytest.raises(ValidationError, match="region_mask"):
        as_object(obj, region_mask=np.zeros(256, dtype=bool))
    (tmp_path / "o.json").write_text(obj.model_dump_json())
    assert object_from_file(tmp_path / "o.json", material="rigid").num_points == 256
    assert as_object(object_points).num_points == 256
    assert as_object({"points": object_points[:, :3].tolist()}).num_points == 256
    assert as_object(str(save_object(obj, tmp_path / "o.npz"))).num_points == 256
    assert as_object(trimesh.creation.icosphere(radius=0.05), num_points=128).num_points == 128
    with pytest.raises(TypeError):
        as_object(3.0)


@settings(max_examples=50, deadline=None)
@given(st.lists(st.floats(-1, 1), min_size=4, max_size=4).filter(lambda q: np.linalg.norm(q) > 0.1))
def test_rotation_matrix_to_quaternion_round_trip(q: list[float]) -> None:
    quat = np.asarray(q) / np.linalg.norm(q)
    matrix = trimesh.transformations.quaternion_matrix(quat)  # (w, x, y, z) like ours
    back = rotation_to_quaternion(matrix)
    assert np.allclose(back, quat, atol=1e-7) or np.allclose(back, -quat, atol=1e-7)
    assert np.allclose(rotation_to_quaternion(matrix[:3, :3]), back)


def test_tasks() -> None:
    transform = trimesh.transformations.rotation_matrix(np.pi / 2, [0, 0, 1])
    transform[:3, 3] = [0.0, 0.0, 0.1]
    task = delta_pose(transform)
    assert isinstance(task, DeltaPoseTask)
    assert np.allclose(task.translation, [0, 0, 0.1])
    assert np.allclose(task.rotation, [np.cos(np.pi / 4), 0, 0, np.sin(np.pi / 4)])
    with pytest.raises(ValidationError, match="identity"):
        delta_pose()
    assert isinstance(target_points(np.zeros((100, 3))), TargetPointsTask)
    assert isinstance(force_closure(), ForceClosureTask)
    assert np.allclose(wrench(force=[0, 0, 1]).wrench, [0, 0, 1, 0, 0, 0])
    assert isinstance(wrench([1, 0, 0]), WrenchTask)
    assert isinstance(as_task("force_closure"), ForceClosureTask)
    assert isinstance(as_task({"kind": "wrench", "wrench": [0, 0, 1, 0, 0, 0]}), WrenchTask)
    with pytest.raises(ValidationError):
        as_task("dance")


def test_make_request_checks_across_fields(object_points: np.ndarray) -> None:
    request = make_request(object_points, target_points(object_points[:, :3] + [0, 0, 0.02]), "leap", seed=4)
    assert request.options.seed == 4 and request.robot.name == "leap"
    assert make_request(request) is request
    with pytest.raises(ValidationError, match="targets"):
        make_request(object_points, target_points(np.zeros((100, 3))))
    with pytest.raises(ValidationError, match="contacts"):
        make_request(object_points, method="contacts")
    with pytest.raises(ValidationError, match="robot"):
        make_request(object_points, robot="Bad Name!")


def test_robot_registration_names(tmp_path: Path) -> None:
    assert robot_registration('<robot name="BH8 Hand">', ["a"]).name == "bh8-hand"
    assert robot_registration(b"<robot/>", ["a"]).name == "custom-hand"
    path = tmp_path / "leap_custom.urdf"
    path.write_text("<robot name='x'/>")
    assert robot_registration(path, ["a"], name=None).name == "leap_custom"
    assert robot_registration(str(path), ["a"], name="mine").name == "mine"
    with pytest.raises(ValidationError, match="tip_offsets"):
        robot_registration(path, ["a"], tip_offsets=[1, 2])


def test_example_data_loads() -> None:
    data = Path(__file__).resolve().parents[3] / "examples" / "data"
    files = sorted(p for p in data.iterdir() if p.suffix in (".npz", ".ply"))
    assert len(files) >= 5
    for path in files:
        obj = object_from_file(path)
        assert obj.num_points >= 1024 and obj.normals is not None, path.name
        outward = np.einsum("ij,ij->i", obj.points - obj.points.mean(axis=0), obj.normals) > 0
        assert outward.mean() > 0.95, path.name
    assert robot_registration(data / "two_finger.urdf", ["left_distal", "right_distal"]).name == "two_finger"
