"""Procedural test objects: seeded, watertight meshes with sampled oriented points.

Used by the refinement evaluation (`mani-lab eval refine`) and by data generation. Every object is centred on its
centre of mass, sized by its largest bounding-box extent, and carries a stable id such as ``box-3f2a9c1e``.

Kinds: ``box``, ``cylinder``, ``sphere``, ``capsule``, ``ellipsoid``, ``convex`` (hull of random points on an
ellipsoid), ``composite`` (non-convex union of 2-4 offset primitives, built as a star-shaped radial mesh) and
``blob`` (non-convex star-shaped body with a random radial profile).
"""

from manifoundation.core.objects.catalog import OBJECT_KINDS, ProceduralObject, make_object, object_set
from manifoundation.core.objects.primitives import radial_union

__all__ = ["OBJECT_KINDS", "ProceduralObject", "make_object", "object_set", "radial_union"]
