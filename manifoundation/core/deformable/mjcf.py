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

Board: plasticine adheres to the board it stands on. Its base (the vertices of its two lowest lattice levels, the
bottom layer of cells, where the second lies in the lower quarter of the body's height: `held_vertices`) is tied to
the world where it rests by ``connect`` equalities of the same stiffness that stay on after the grasps are released,
so a press dents the body instead of sliding or rolling it across the table. The lowest level alone was measured
too: on a blob or composite that touches the board with one cube's face (4 vertices) the body then topples under its
own weight (1.7-24 mm mean drift with nothing pressed); with the bottom layer of cells held, every one of 14 such
bodies stays within 0.2 mm (docs/deformables.md). A grasped base vertex is the grasp's, not the board's. Cloth and
rope lie free.
"""

from __future__ import annotations

import numpy as np

from manifoundation.core.deformable.body import DeformableBody
from manifoundation.core.deformable.materials import flex_parameters

FLEX_NAME = "obj"
RADIUS = {"cloth": 0.004, "rope": 0.001, "plasticine": 0.001}
DAMPING = {"cloth": 1e-3, "rope": 1e-3, "plasticine": 1e-3}
HELD_MATERIALS = ("plasticine",)
BASE_LEVELS = 2  # distinct vertex heights from the bottom that the board holds (a lattice's bottom layer of cells)
BASE_SHARE = 0.25  # … those of them in this lower share of the body's height (a flat box: its bottom level only)
LEVEL = 1e-6  # × the body's size: heights closer than this are one level


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


def held_vertices(body: DeformableBody, grasped: np.ndarray) -> np.ndarray:
    """Vertex indices (B,) the board holds: a plasticine body's lowest vertex height and the next ones up to
    `BASE_LEVELS` in all, those within `BASE_SHARE` of its height, less the ``grasped`` (H,) vertices; none for
    cloth and rope."""
    if body.material not in HELD_MATERIALS:
        return np.zeros(0, dtype=np.int64)
    z = np.asarray(body.vertices, dtype=np.float64)[:, 2]
    tol = LEVEL * max(body.size, 1e-9)
    levels = np.unique(np.round((z - z.min()) / tol)) * tol  # heights above the lowest vertex
    base = levels[:BASE_LEVELS]
    cut = z.min() + float(base[(base <= BASE_SHARE * levels[-1]) | (base == 0.0)].max()) + 0.5 * tol
    held: np.ndarray = np.setdiff1d(np.flatnonzero(z <= cut), np.asarray(grasped, dtype=np.int64))
    return held


def scene_xml(body: DeformableBody, grasped: np.ndarray, timestep: float) -> str:
    """MJCF text of the table, the body, one mocap grasp per vertex in ``grasped`` (H,) and the board's hold on a
    plasticine base (`held_vertices`); the grasps' equalities come first, one per grasped vertex."""
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
    welds += "".join(
        f'<connect body1="{FLEX_NAME}_{int(i)}" anchor="0 0 0" solref="{ref}" solimp="0.99 0.999 0.001"/>'
        for i in held_vertices(body, grasped)
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
