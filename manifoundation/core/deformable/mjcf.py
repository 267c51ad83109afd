"""The MJCF scene of one simulation: table plane, the body as a MuJoCo flex, and one grasp per contact.

Flex: ``<flexcomp type="direct">`` with the body's vertices and elements (dim 2 cloth, 3 rope and plasticine),
elasticity from `materials.flex_parameters` (cloth: shell with stretch and bending; rope: a solid rod, so its
bending follows E; plasticine: 3D elasticity with von Mises yield), every vertex its own body (``obj_<i>``).
MuJoCo 4.0 integrates flex elasticity stably only with the ``discrete`` integrator (implicit integrators refuse
it, explicit Euler needs ≤ 0.5 ms steps; see docs/deformables.md).

Grasp: a mocap body ``grip<k>`` starts at the grasped vertex and a ``connect`` equality ties the two; the
mocap is then driven along the contact's path. The equality's time constant is two steps (MuJoCo's safe floor)
and its impedance near 1 (solimp 0.99-0.999), which holds a vertex against the stiffest plasticine in our ranges
(measured: 1.5 cm press tracked to < 1 mm).
"""

from __future__ import annotations

import numpy as np

from manifoundation.core.deformable.body import DeformableBody
from manifoundation.core.deformable.materials import flex_parameters

FLEX_NAME = "obj"
RADIUS = {"cloth": 0.004, "rope": 0.001, "plasticine": 0.001}
DAMPING = {"cloth": 1e-3, "rope": 1e-3, "plasticine": 1e-3}


def oriented_elements(body: DeformableBody) -> np.ndarray:
    """Elements with positive orientation: triangles counter-clockwise seen from +z, tetrahedra of positive volume."""
    v, e = np.asarray(body.vertices), np.array(body.elements, copy=True)
    if body.material == "cloth":
        n = np.cross(v[e[:, 1]] - v[e[:, 0]], v[e[:, 2]] - v[e[:, 0]])[:, 2]
        e[n < 0] = e[n < 0][:, [0, 2, 1]]
    else:
        vol = np.einsum("ij,ij->i", v[e[:, 1]] - v[e[:, 0]], np.cross(v[e[:, 2]] - v[e[:, 0]], v[e[:, 3]] - v[e[:, 0]]))
        e[vol < 0] = e[vol < 0][:, [0, 2, 1, 3]]
    return e


def _numbers(a: np.ndarray) -> str:
    return " ".join(f"{x:.6g}" for x in np.asarray(a).reshape(-1))


def scene_xml(body: DeformableBody, grasped: np.ndarray, timestep: float) -> str:
    """MJCF text of the table, the body and one mocap grasp per vertex in ``grasped`` (H,)."""
    p = flex_parameters(body.material, body.properties, body.measure())
    v = np.asarray(body.vertices, dtype=np.float64)
    dim = 2 if body.material == "cloth" else 3
    elastic = f'young="{p.young:.6g}" poisson="{p.poisson:.6g}" damping="{DAMPING[body.material]:.3g}"'
    if body.material == "cloth":
        elastic += f' thickness="{p.thickness:.6g}" elastic2d="both"'
    if p.yield_strain > 0:
        elastic += f' yield="{p.yield_strain:.6g}"'
    grips = "".join(f'<body name="grip{k}" mocap="true" pos="{_numbers(v[i])}"/>' for k, i in enumerate(grasped))
    ref = f"{2 * timestep:.6g} 1"
    welds = "".join(
        f'<connect body1="grip{k}" body2="{FLEX_NAME}_{int(i)}" anchor="0 0 0" solref="{ref}" '
        'solimp="0.99 0.999 0.001"/>'
        for k, i in enumerate(grasped)
    )
    return f"""<mujoco model="deformable">
  <option timestep="{timestep:.6g}" integrator="discrete" solver="CG" tolerance="1e-6" iterations="200"/>
  <size memory="64M"/>
  <worldbody>
    <geom name="table" type="plane" size="5 5 0.1" friction="{p.friction:.6g} 0.005 0.0001"/>
    {grips}
    <flexcomp name="{FLEX_NAME}" type="direct" dim="{dim}" radius="{RADIUS[body.material]}" mass="{p.mass:.6g}"
              point="{_numbers(v)}" element="{_numbers(oriented_elements(body))}">
      <contact condim="3" friction="{p.friction:.6g} 0.005 0.0001" solref="0.01 1" solimp=".95 .99 .0001"
               selfcollide="none"/>
      <elasticity {elastic}/>
    </flexcomp>
  </worldbody>
  <equality>{welds}</equality>
</mujoco>"""
