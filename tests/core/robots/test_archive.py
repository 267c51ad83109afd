"""Hostile hand archives: each refused with a `HandLoadError` that names the problem, nothing read outside.

The archives are built here with the standard library (a real zip bomb, a real 10^7-face STL, real symlinks), and
the same checks run through the API in `tests/api/test_custom_hands.py`.
"""

from __future__ import annotations

import io
import struct
import tarfile
import time
import zipfile

import numpy as np
import pytest
import trimesh

from manifoundation.core.robots.archive import MAX_MEMBERS, HandArchive, read_archive
from manifoundation.core.robots.description import HandLoadError
from manifoundation.core.robots.user_hand import HandSource, build_user_hand

URDF = """<robot name="r">
  <link name="palm"><collision><geometry><box size="0.05 0.05 0.01"/></geometry></collision></link>
  <link name="tip"><collision><geometry><mesh filename="{mesh}"/></geometry></collision></link>
  <joint name="j" type="revolute"><parent link="palm"/><child link="tip"/><origin xyz="0 0 0.02"/>
    <axis xyz="1 0 0"/><limit lower="0" upper="1"/></joint>
</robot>"""


def stl_bytes(mesh: trimesh.Trimesh) -> bytes:
    return bytes(mesh.export(file_type="stl"))


def zip_of(files: dict[str, bytes], method: int = zipfile.ZIP_DEFLATED) -> bytes:
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", method) as z:
        for name, data in files.items():
            z.writestr(name, data)
    return buf.getvalue()


def tar_of(members: list[tuple[tarfile.TarInfo, bytes | None]]) -> bytes:
    buf = io.BytesIO()
    with tarfile.open(fileobj=buf, mode="w:gz") as t:
        for info, data in members:
            t.addfile(info, io.BytesIO(data) if data is not None else None)
    return buf.getvalue()


def good_files() -> dict[str, bytes]:
    return {
        "hand/urdf/hand.urdf": URDF.format(mesh="package://hand/meshes/tip.stl").encode(),
        "hand/meshes/tip.stl": stl_bytes(trimesh.creation.box(extents=[0.01, 0.01, 0.03])),
    }


def refused(data: bytes, *words: str) -> str:
    with pytest.raises(HandLoadError) as info:
        build_user_hand(HandSource(name="x", archive=data))
    message = str(info.value)
    for word in words:
        assert word in message, message
    return message


def test_a_good_archive_keeps_the_mesh_collision_geometry() -> None:
    built = build_user_hand(HandSource(name="x", archive=zip_of(good_files())))
    assert built.fingertips == ["tip"] and built.meshes == 1
    tip = built.hand.collision_meshes["tip"]
    assert np.allclose(tip.extents, [0.01, 0.01, 0.03])  # the STL box, not a primitive stand-in
    # the same hand as a gzip'd tar, relative mesh path
    files = good_files()
    files["hand/urdf/hand.urdf"] = URDF.format(mesh="../meshes/tip.stl").encode()
    members = []
    for name, data in files.items():
        info = tarfile.TarInfo(name)
        info.size = len(data)
        members.append((info, data))
    assert build_user_hand(HandSource(name="x", archive=tar_of(members))).meshes == 1


def test_zip_bomb() -> None:
    bomb = zip_of(good_files() | {"hand/meshes/pad.obj": b"\0" * (40 * 1024 * 1024)})
    assert len(bomb) < 100_000
    refused(bomb, "pad.obj", "zip bomb")


def test_path_traversal_and_absolute_names() -> None:
    refused(zip_of(good_files() | {"../../etc/cron.d/x": b"x"}), "../../etc/cron.d/x", "traversal")
    refused(zip_of(good_files() | {"/etc/passwd": b"x"}), "/etc/passwd", "absolute")
    # a description naming a file outside the archive, three ways
    for ref in ("../../../../etc/passwd", "/etc/passwd", "file:///etc/passwd"):
        files = good_files() | {"hand/urdf/hand.urdf": URDF.format(mesh=ref).encode()}
        refused(zip_of(files), ref)


def test_symlinks_and_devices() -> None:
    link = zipfile.ZipInfo("hand/meshes/tip.stl")
    link.external_attr = (0o120777 << 16) | 0x20
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w") as z:
        z.writestr("hand/urdf/hand.urdf", good_files()["hand/urdf/hand.urdf"])
        z.writestr(link, "/etc/passwd")
    refused(buf.getvalue(), "tip.stl", "symbolic link")
    sym = tarfile.TarInfo("hand/meshes/tip.stl")
    sym.type, sym.linkname = tarfile.SYMTYPE, "/etc/passwd"
    refused(tar_of([(sym, None)]), "tip.stl", "symbolic")
    dev = tarfile.TarInfo("hand/meshes/tip.stl")
    dev.type, dev.devmajor, dev.devminor = tarfile.CHRTYPE, 1, 3
    refused(tar_of([(dev, None)]), "tip.stl", "device")


def test_ten_thousand_members() -> None:
    files = good_files() | {f"junk/{i}.txt": b"" for i in range(10_000)}
    start = time.perf_counter()
    refused(zip_of(files, zipfile.ZIP_STORED), str(MAX_MEMBERS), "members")
    assert time.perf_counter() - start < 5.0


def test_a_mesh_of_ten_million_faces() -> None:
    faces = 10_000_000
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", zipfile.ZIP_DEFLATED, compresslevel=1) as z:
        z.writestr("hand/urdf/hand.urdf", good_files()["hand/urdf/hand.urdf"])
        with z.open("hand/meshes/tip.stl", "w", force_zip64=True) as f:  # a real one: 500 MB of triangles
            f.write(b"\0" * 80 + struct.pack("<I", faces))
            block = b"\0" * (50 * 100_000)
            for _ in range(faces // 100_000):
                f.write(block)
    refused(buf.getvalue(), "tip.stl", "10000000 faces")


def test_a_description_naming_a_missing_file() -> None:
    files = good_files()
    del files["hand/meshes/tip.stl"]
    refused(zip_of(files), "package://hand/meshes/tip.stl", "not in the archive")


def test_not_an_archive_and_no_description() -> None:
    with pytest.raises(HandLoadError, match="not a zip or tar"):
        read_archive(b"hello")
    refused(zip_of({"meshes/tip.stl": good_files()["hand/meshes/tip.stl"]}), "no .urdf")


def test_package_references_resolve_by_their_longest_tail() -> None:
    archive = HandArchive({"a/meshes/x.stl": b"", "b/meshes/x.stl": b"", "meshes/y.stl": b""})
    assert archive.resolve("package://pkg/a/meshes/x.stl") == "a/meshes/x.stl"
    assert archive.resolve("package://other/meshes/y.stl") == "meshes/y.stl"
    with pytest.raises(HandLoadError, match="not in the archive"):
        archive.resolve("package://pkg/c/x.stl")  # two x.stl: a bare name is ambiguous


def test_an_obj_over_the_face_limit_is_refused_before_it_is_parsed() -> None:
    """Its ``f`` lines are counted on the bytes, so the refusal costs a fraction of the parse (issue 62, item 10: a
    1.2 M-face OBJ cost 10.5 s of worker time, parsed, before its size was checked)."""
    faces = 700_000
    rng = np.random.default_rng(0)
    vertices = b"".join(b"v %.4f %.4f %.4f\n" % tuple(v) for v in rng.random((1000, 3))) + b"vn 0 0 1\n"
    corners = rng.integers(1, 1001, size=(faces, 3))
    obj = vertices + b"".join(b"f %d//1 %d//1 %d//1\n" % tuple(f) for f in corners)
    files = {"hand/urdf/hand.urdf": URDF.format(mesh="package://hand/meshes/tip.obj").encode(),
             "hand/meshes/tip.obj": obj}  # fmt: skip
    archive = zip_of(files)
    started = time.process_time()
    refused(archive, "tip.obj", f"{faces} faces")
    refusal = time.process_time() - started
    started = time.process_time()
    trimesh.load(io.BytesIO(obj), file_type="obj", force="mesh", process=False)
    parse = time.process_time() - started
    assert refusal < parse / 2, (refusal, parse)
