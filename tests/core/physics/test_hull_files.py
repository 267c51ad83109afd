"""The hand's hulls given to MuJoCo as files (its asset cache then builds each once per process): the compiled
model is the one ``uservert`` gave, to the bit, and the files are named by their content."""

from __future__ import annotations

import os

import mujoco
import numpy as np

from manifoundation.core.physics.hand_model import _hull_vertices
from manifoundation.core.physics.hull_files import hull_file
from manifoundation.core.physics.visual import physics_description
from manifoundation.core.robots.registry import get_hand

FIELDS = ("mesh_vert", "mesh_vertnum", "mesh_graph", "mesh_graphadr", "mesh_pos", "mesh_quat", "body_mass",
          "body_inertia", "body_ipos", "body_iquat", "geom_size", "geom_rbound", "geom_aabb", "geom_pos",
          "geom_quat")  # fmt: skip


def _model(hulls: list[np.ndarray], by_file: bool) -> mujoco.MjModel:
    spec = mujoco.MjSpec()
    body = spec.worldbody.add_body(name="hand")
    for k, v in enumerate(hulls):
        if by_file:
            spec.add_mesh(name=f"m{k}", file=hull_file(v))
        else:
            spec.add_mesh(name=f"m{k}", uservert=v.astype(np.float32).reshape(-1).tolist())
        body.add_geom(type=mujoco.mjtGeom.mjGEOM_MESH, meshname=f"m{k}")
    return spec.compile()


def test_hulls_by_file_compile_to_the_same_model() -> None:
    for name in ("allegro", "leap"):
        desc = physics_description(get_hand(name))
        hulls = [_hull_vertices(m) for meshes in desc.links.values() for m in meshes
                 if len(m.vertices) >= 4 and m.extents.min() >= 1e-5]  # fmt: skip
        by_vertices, by_file, again = _model(hulls, False), _model(hulls, True), _model(hulls, True)
        for field in FIELDS:
            want = getattr(by_vertices, field)
            assert np.array_equal(getattr(by_file, field), want), (name, field)
            assert np.array_equal(getattr(again, field), want), (name, field)  # from MuJoCo's cache


def test_hull_files_are_named_by_their_content() -> None:
    v = np.random.default_rng(0).normal(size=(20, 3))
    first, same, other = hull_file(v), hull_file(v.copy()), hull_file(v + 1e-3)
    assert first == same != other and os.path.exists(first)
    with open(first, "rb") as f:
        head = np.frombuffer(f.read(16), dtype="<i4")
    assert list(head) == [20, 0, 0, 0] and os.path.getsize(first) == 16 + 20 * 3 * 4
