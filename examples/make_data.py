"""Regenerate the small example inputs in ``examples/data/`` (committed; run this only to change them).

Objects come from the project's own seeded generator (`manifoundation.core.objects`), so they are the same shapes the
evaluation uses; each is saved with its oriented points and its mesh. Needs the full install (trimesh); the
other examples need only the SDK.

    .venv/bin/python examples/make_data.py
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

DATA = Path(__file__).resolve().parent / "data"
NUM_POINTS = 1024

# (file name, kind, largest extent in metres, seed)
OBJECTS = [
    ("box.npz", "box", 0.08, 1),
    ("cylinder.npz", "cylinder", 0.10, 2),
    ("composite.npz", "composite", 0.09, 3),
    ("convex.npz", "convex", 0.07, 4),
]
MESH_FILES = [("blob.ply", "blob", 0.08, 5)]
CLOUD_FILES = [("sphere_cloud.ply", "sphere", 0.06, 6)]
# Deformable requests without a robot: (file name, material, shape kind, seed). The target is where the
# project's own simulator takes the body under the data generator's procedure for that material.
DEFORMABLE_REQUESTS = [
    ("cloth_fold.json", "cloth", "towel", 1),
    ("rope_drag.json", "rope", "rope", 2),
    ("plasticine_press.json", "plasticine", "blob", 3),
]

TWO_FINGER_URDF = """<?xml version="1.0" encoding="utf-8"?>
<!-- A minimal two-finger gripper for the "register a custom hand" example: a 60x30x20 mm palm box, two fingers
     of two revolute joints each (box links), primitive collision geometry only (user URDFs never load meshes).
     Palm frame: +z is the approach direction; the fingers sit at y = -/+20 mm and close towards each other. -->
<robot name="two_finger">
  <link name="palm">
    <collision><origin xyz="0 0 0.01"/><geometry><box size="0.06 0.03 0.02"/></geometry></collision>
  </link>
  <link name="left_proximal">
    <collision><origin xyz="0 0 0.025"/><geometry><box size="0.018 0.012 0.05"/></geometry></collision>
  </link>
  <link name="left_distal">
    <collision><origin xyz="0 0 0.02"/><geometry><box size="0.016 0.01 0.04"/></geometry></collision>
  </link>
  <link name="right_proximal">
    <collision><origin xyz="0 0 0.025"/><geometry><box size="0.018 0.012 0.05"/></geometry></collision>
  </link>
  <link name="right_distal">
    <collision><origin xyz="0 0 0.02"/><geometry><box size="0.016 0.01 0.04"/></geometry></collision>
  </link>
  <joint name="left_base" type="revolute">
    <parent link="palm"/><child link="left_proximal"/>
    <origin xyz="0 -0.02 0.02"/><axis xyz="1 0 0"/><limit lower="-0.6" upper="0.6" effort="5" velocity="2"/>
  </joint>
  <joint name="left_tip" type="revolute">
    <parent link="left_proximal"/><child link="left_distal"/>
    <origin xyz="0 0 0.05"/><axis xyz="1 0 0"/><limit lower="-1.2" upper="0.2" effort="5" velocity="2"/>
  </joint>
  <joint name="right_base" type="revolute">
    <parent link="palm"/><child link="right_proximal"/>
    <origin xyz="0 0.02 0.02"/><axis xyz="1 0 0"/><limit lower="-0.6" upper="0.6" effort="5" velocity="2"/>
  </joint>
  <joint name="right_tip" type="revolute">
    <parent link="right_proximal"/><child link="right_distal"/>
    <origin xyz="0 0 0.05"/><axis xyz="1 0 0"/><limit lower="-0.2" upper="1.2" effort="5" velocity="2"/>
  </joint>
</robot>
"""


def _make(kind: str, size: float, seed: int):  # type: ignore[no-untyped-def]
    from manifoundation.core.objects import make_object

    return make_object(kind, size, seed, NUM_POINTS)


def _deformable_request(material: str, kind: str, seed: int) -> dict[str, object]:
    """A request body: the body's cloud, the motion its procedure gives every point, simulated rollout asked (the
    press: its pushed cluster as given contacts, the motions corrected by up to 6 rollouts)."""
    from manifoundation.core.deformable.procedures import cloth_fold, plasticine_push, rope_drag
    from manifoundation.core.deformable.shapes import make_body
    from manifoundation.core.deformable.simulate import simulate

    body = make_body(material, kind, seed)
    procedure = {"cloth": cloth_fold, "rope": rope_drag, "plasticine": plasticine_push}[material]
    manipulation = procedure(body, np.random.default_rng(seed))
    target = simulate(body, manipulation.contacts, manipulation.motions).cloud
    request: dict[str, object] = {
        "object": {"points": body.points.round(5).tolist(), "normals": body.normals.round(4).tolist(),
                   "material": material, "properties": body.properties},
        "task": {"kind": "point_motion", "motion": (target - body.points).round(5).tolist()},
        "options": {"num_proposals": 2, "seed": seed, "simulate_rollout": True, "timeout": 60},
    }  # fmt: skip
    if material == "plasticine":
        request["contacts"] = {"points": body.points[manipulation.contacts].round(5).tolist()}
        request["options"] = {"method": "contacts", "num_contacts": len(manipulation.contacts), "seed": seed,
                              "simulate_rollout": True, "rollout_corrections": 6, "timeout": 60}  # fmt: skip
    return request


def main() -> None:
    DATA.mkdir(exist_ok=True)
    for name, kind, size, seed in OBJECTS:
        obj = _make(kind, size, seed)
        np.savez_compressed(
            DATA / name,
            points=obj.points.astype(np.float32),
            normals=obj.normals.astype(np.float32),
            vertices=np.asarray(obj.mesh.vertices, dtype=np.float32),
            faces=np.asarray(obj.mesh.faces, dtype=np.int32),
        )
    for name, kind, size, seed in MESH_FILES:
        _make(kind, size, seed).mesh.export(DATA / name)
    for name, kind, size, seed in CLOUD_FILES:
        obj = _make(kind, size, seed)
        rows = np.hstack([obj.points, obj.normals])
        header = ["ply", "format ascii 1.0", f"element vertex {len(rows)}"]
        header += [f"property float {axis}" for axis in ("x", "y", "z", "nx", "ny", "nz")] + ["end_header"]
        body = [" ".join(f"{v:.6f}" for v in row) for row in rows]
        (DATA / name).write_text("\n".join(header + body) + "\n")
    (DATA / "two_finger.urdf").write_text(TWO_FINGER_URDF)
    for name, material, kind, seed in DEFORMABLE_REQUESTS:
        (DATA / name).write_text(json.dumps(_deformable_request(material, kind, seed)))
    for path in sorted(DATA.iterdir()):
        print(f"{path.relative_to(DATA.parent)}  {path.stat().st_size / 1024:.0f} KiB")


if __name__ == "__main__":
    main()
