"""Validate a `SynthesisInput` and derive what every stage needs (field, mass, task, contact sets)."""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np

from manifoundation.core.errors import InvalidContacts
from manifoundation.core.geometry.object import DEFAULT_DENSITY, DEFAULT_FRICTION, ObjectGeometry
from manifoundation.core.geometry.spread import spread_contacts
from manifoundation.core.pipeline.object_cache import ObjectCache, PreparedObject, default_cache, digest
from manifoundation.core.pipeline.tasks import build_task, network_motion
from manifoundation.core.pipeline.types import MATERIALS, METHODS, InvalidInput, SynthesisInput
from manifoundation.core.refine.field import PointCloudField
from manifoundation.core.refine.surface_samples import object_field
from manifoundation.core.refine.wrench import WrenchTask

MAX_GIVEN_OFFSET = 0.01  # m: a given contact farther than this from the object's surface is refused (422)


@dataclass
class Prepared:
    """A validated input with its derived quantities."""

    inp: SynthesisInput
    cloud: PointCloudField
    mesh: Any | None
    centre: np.ndarray
    mass: float
    inertia: np.ndarray
    task: WrenchTask
    mu: float
    tip_field: Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]] | None
    seconds: float


def _array(name: str, value: Any, shape: tuple[int | None, ...]) -> np.ndarray:
    arr = np.asarray(value, dtype=np.float64)
    if arr.ndim != len(shape) or any(s is not None and s != a for s, a in zip(shape, arr.shape, strict=True)):
        raise InvalidInput(f"{name}: expected shape {tuple('N' if s is None else s for s in shape)}, got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise InvalidInput(f"{name}: contains NaN or inf")
    return arr


def prepare(inp: SynthesisInput, cache: ObjectCache | None = None) -> Prepared:
    """Check shapes and options, estimate normals if missing, compute mass properties and the task residual.

    What the object alone determines (mesh structures, point field, normals, mass) comes from ``cache``
    (`manifoundation.core.pipeline.object_cache`; default: the process's) when the same bytes were prepared before."""
    t0 = time.perf_counter()
    points = _array("points", inp.points, (None, 3))
    n = len(points)
    if n < 16:
        raise InvalidInput(f"points: {n} points, need at least 16")
    if inp.method not in METHODS:
        raise InvalidInput(f"method: {inp.method!r} is not one of {', '.join(METHODS)}")
    if inp.material not in MATERIALS:
        raise InvalidInput(f"material: {inp.material!r} is not one of {', '.join(MATERIALS)}")
    if inp.num_proposals < 1 or inp.max_iterations < 1:
        raise InvalidInput("num_proposals and max_iterations must be ≥ 1")
    mask = None
    if inp.mask is not None:
        mask = np.asarray(inp.mask).astype(bool).reshape(-1)
        if mask.shape != (n,) or not mask.any():
            raise InvalidInput(f"mask: expected ({n},) with at least one allowed point")
    vertices = faces = None
    if inp.mesh_vertices is not None and inp.mesh_faces is not None:
        vertices = _array("mesh.vertices", inp.mesh_vertices, (None, 3))
        faces = np.asarray(inp.mesh_faces, dtype=np.int64)
    normals = None if inp.normals is None else _array("normals", inp.normals, (n, 3))
    density = float(inp.properties.get("density", DEFAULT_DENSITY))
    obj = _object(points, normals, mask, vertices, faces, cache)
    exact, cloud = obj.exact, obj.cloud
    mp = obj.mass_properties(density)
    centre = np.asarray(mp.com, dtype=np.float64)
    inertia = np.asarray(mp.inertia, dtype=np.float64)
    if inp.joint is not None:
        if inp.joint.type not in ("revolute", "prismatic"):
            raise InvalidInput(f"joint.type: {inp.joint.type!r} is not revolute or prismatic")
        _array("joint.axis", inp.joint.axis, (3,))
        _array("joint.origin", inp.joint.origin, (3,))
    task = build_task(inp.task, points, mp.mass, centre, inertia, inp.joint)
    mu = float(inp.properties.get("friction", DEFAULT_FRICTION))
    if not 0 < mu <= 5:
        raise InvalidInput(f"properties.friction: {mu} is outside (0, 5]")
    tip_field = cloud.region_distance if mask is not None else None
    if inp.initial_pose is not None:
        _initial_pose(inp)
    elif inp.method == "contacts":
        if inp.contacts is None:
            raise InvalidInput("contacts: required with method 'contacts'")
        contacts = _array("contacts", inp.contacts, (None, 3))
        if not 1 <= len(contacts) <= inp.hand.num_fingertips:
            raise InvalidInput(
                f"contacts: {len(contacts)} contacts for a hand with {inp.hand.num_fingertips} fingertips"
            )
        off = np.abs(cloud.signed_distance(contacts)[0])
        if float(off.max()) > MAX_GIVEN_OFFSET:
            i = int(np.argmax(off))
            raise InvalidContacts(
                f"contacts.points: point {i} lies {off[i]:.3f} m from the object's surface, more than "
                f"{MAX_GIVEN_OFFSET} m: given contacts must be on the object"
            )
    return Prepared(inp, cloud, exact, centre, mp.mass, inertia, task, mu, tip_field, time.perf_counter() - t0)


def _object(points: np.ndarray, normals: np.ndarray | None, mask: np.ndarray | None, vertices: np.ndarray | None,
            faces: np.ndarray | None, cache: ObjectCache | None) -> PreparedObject:  # fmt: skip
    """The object's mesh, geometry, exact surface and point field, from ``cache`` or built (a bad object raises
    `InvalidInput` and is not kept)."""
    cache = default_cache if cache is None else cache
    mesh_key, mesh = b"", None
    if vertices is not None and faces is not None:
        mesh_key = digest(vertices, faces)
        mesh = cache.mesh(mesh_key, vertices, faces)

    def build() -> PreparedObject:
        own = points.copy()  # kept beyond this request: not the caller's array
        try:
            geom = ObjectGeometry.from_points(own, None if normals is None else normals.copy(), mesh)
        except ValueError as exc:
            raise InvalidInput(str(exc)) from exc
        exact = mesh if mesh is not None and mesh.is_watertight else None  # else the points' surface, never a hull
        # a sparse cloud: distances on the mesh's samples too
        cloud = object_field(own, geom.normals, None if mask is None else mask.copy(), exact)
        return PreparedObject(mesh, geom, exact, cloud)

    return cache.prepared(digest(points, normals, mask) + mesh_key, build)  # the mesh's bytes hashed once


def _initial_pose(inp: SynthesisInput) -> None:
    """Check a caller's start pose: palm position (3,), unit quaternion (4,), one value per finger joint."""
    pose = inp.initial_pose
    assert pose is not None
    _array("initial_pose.palm_pos", pose.palm_pos, (3,))
    quat = _array("initial_pose.palm_quat", pose.palm_quat, (4,))
    if abs(float(np.linalg.norm(quat)) - 1.0) > 1e-6:
        raise InvalidInput("initial_pose.palm_quat: not a unit quaternion")
    _array("initial_pose.q", pose.q, (inp.hand.dof,))


def network_inputs(batch: Sequence[Prepared]) -> list[Any]:
    """`manifoundation.core.network.inference.NetworkInput` rows for the predictor."""
    from manifoundation.core.network.inference import NetworkInput

    rows = []
    for p in batch:
        inp, hand = p.inp, p.inp.hand
        mask = p.cloud.mask if p.cloud.mask is not None else np.ones(len(p.cloud.points), dtype=bool)
        rows.append(
            NetworkInput(
                points=p.cloud.points,
                normals=p.cloud.normals,
                motion=network_motion(inp.task, p.cloud.points, p.centre, p.mass, p.inertia, inp.joint),
                mask=mask,
                properties={k: v for k, v in inp.properties.items() if k != "yield_stress"},  # not a channel
                hand_points=np.asarray(hand.surface_points),
                hand_normals=np.asarray(hand.surface_normals),
                hand_key=str(inp.hand_key or hand.name),
            )
        )
    return rows


class ContactSet(NamedTuple):
    """One proposal's contacts before the hand is placed on them."""

    points: np.ndarray  # (H, 3)
    normals: np.ndarray  # (H, 3)
    heat: np.ndarray | None  # (N,) the predicted heatmap the contacts came from, when from the network
    source: str  # given | random | network | random_fallback
    forces: np.ndarray | None = None  # (H, 3) the network's force/motion prediction at the contacts
    sample: int | None = None  # which of the network's K samples


def contact_sets(prep: Prepared, net_out: Any | None) -> list[ContactSet]:
    """One `ContactSet` per candidate start (`SynthesisInput.candidates`).

    ``source`` says where the contacts came from: "given", "random", "network", "opposed" (force closure:
    `opposed_sets`) or "random_fallback" when the network's heatmap had no point above the selection threshold
    (the answer then says so).
    """
    inp, cloud = prep.inp, prep.cloud
    m = inp.hand.num_fingertips
    allowed = np.flatnonzero(cloud.mask) if cloud.mask is not None else np.arange(len(cloud.points))
    rng = np.random.default_rng(inp.seed)

    def random_set(source: str = "random") -> ContactSet:
        sub = allowed[spread_contacts(cloud.points[allowed], min(m, len(allowed)), rng)]
        return ContactSet(cloud.points[sub], cloud.normals[sub], None, source)

    if inp.method == "contacts":
        assert inp.contacts is not None
        pts = np.asarray(inp.contacts, dtype=np.float64)
        idx = cloud.nearest_index(pts)
        return [ContactSet(cloud.points[idx], cloud.normals[idx], None, "given")] * inp.candidates
    if inp.method == "random_contacts" or net_out is None:
        return [random_set() for _ in range(inp.candidates)]
    if prep.task.closure and m == 2:  # a gripper holding it: its two pads opposed across the object
        return opposed_sets(prep, net_out, rng, allowed)

    from manifoundation.core.network.selection import select_contacts

    sets: list[ContactSet] = []
    for k in range(inp.candidates):
        heat, force = net_out.heatmaps[k], net_out.force_maps[k]
        sel = select_contacts(cloud.points, heat, force, cloud.mask, m)
        if len(sel) == 0:  # nothing above threshold: fall back to random contacts in the region
            sets.append(random_set("random_fallback"))
            continue
        heat64 = np.asarray(heat, dtype=np.float64)
        forces = np.asarray(sel.forces, dtype=np.float64)
        sets.append(ContactSet(sel.points, cloud.normals[sel.indices], heat64, "network", forces, k))
    if prep.task.closure and len(sets) > 1:  # every other candidate opposed: what the network does not offer
        opposed = opposed_sets(prep, net_out, rng, allowed)
        sets = [opposed[k // 2] if k % 2 else s for k, s in enumerate(sets)]
    return sets


def opposed_sets(prep: Prepared, net_out: Any | None, rng: np.random.Generator, allowed: np.ndarray
                 ) -> list[ContactSet]:  # fmt: skip
    """`SynthesisInput.candidates` opposed contact sets (`manifoundation.core.geometry.opposition`), drawn in
    proportion to the network's first heatmap when there is one; random ones (``random_fallback``) where the object
    has too few opposed pairs within the hand's rest opening.

    Every candidate of a two-fingertip hand asked to hold the object (on 43 third-party objects the Panda
    gripper's first answer held in 15, network contacts 10); every other candidate of the other hands, the network's
    first (first answers that held, opposed vs network: Shadow 26 vs 17, Kinova 23 vs 19, Barrett 15 vs 13, but
    LEAP 7 vs 8, LEAP Hand 10 vs 12, Allegro 3 vs 9; best of four alternating vs network only: LEAP 23 vs 24,
    Allegro 17 vs 18, Panda 28 vs 17; research/results/physics.md)."""
    from manifoundation.core.geometry.opposition import opposed_contacts
    from manifoundation.core.refine.initialise import opposition, rest_geometry

    inp, cloud = prep.inp, prep.cloud
    m = inp.hand.num_fingertips
    rest = rest_geometry(inp.hand)
    thumb, others = opposition(rest)
    width = float(np.linalg.norm(thumb - others))
    spacing = _finger_spacing(rest.tips, thumb)
    region = np.zeros(len(cloud.points), bool)
    region[allowed] = True
    heat = None if net_out is None else np.asarray(net_out.heatmaps[0], dtype=np.float64)
    found = opposed_contacts(cloud.points, cloud.normals, m, spacing, width, inp.candidates, rng, heat, region)
    sets = [ContactSet(cloud.points[o.indices], cloud.normals[o.indices], None, "opposed") for o in found]
    while len(sets) < inp.candidates:
        sub = allowed[spread_contacts(cloud.points[allowed], min(m, len(allowed)), rng)]
        sets.append(ContactSet(cloud.points[sub], cloud.normals[sub], None, "random_fallback"))
    return sets


def _finger_spacing(tips: np.ndarray, thumb: np.ndarray) -> float:
    """Median distance (m) from each non-thumb fingertip (rest pose, (m, 3)) to its nearest neighbour; 0 with one."""
    others = np.delete(tips, int(np.argmin(np.linalg.norm(tips - thumb, axis=1))), axis=0)
    if len(others) < 2:
        return 0.0
    d = np.linalg.norm(others[:, None] - others[None], axis=2)
    np.fill_diagonal(d, np.inf)
    return float(np.median(d.min(axis=1)))
