"""Objects an agent uploaded once and names by id afterwards: per tenant, with a time to live and size limits.

An LLM agent should not paste a point cloud into every call: ``upload_object`` validates the object once with
the contract (`ObjectIn`) and answers an id; the other tools take that id. Each tenant (API key) has its own
namespace: another tenant's id is unknown to it, like an id that never existed. Limits
(`manifoundation.server.api.settings`):
``object_ttl_s`` after the last use, ``max_objects`` per tenant, ``max_object_store_bytes`` of arrays per tenant
(the least recently used objects are not evicted to make room: the upload is refused, naming the limit).

In memory, per process: behind several replicas an object lives on the replica that took the upload (route an
agent's session to one replica, or upload again).
"""

from __future__ import annotations

import secrets
import time
from collections import OrderedDict
from dataclasses import dataclass

import numpy as np

from manifoundation.contract import FieldError, ObjectIn
from manifoundation.server.api.errors import Conflict, NotFound


def object_bytes(obj: ObjectIn) -> int:
    """The bytes of an object's arrays (points, normals, mesh, masks)."""
    arrays = [obj.points, obj.normals, obj.region_mask]
    if obj.mesh is not None:
        arrays += [obj.mesh.vertices, obj.mesh.faces]
    if obj.joint is not None:
        arrays.append(obj.joint.part_mask)
    return int(sum(np.asarray(a).nbytes for a in arrays if a is not None))


@dataclass
class StoredObject:
    """One uploaded object."""

    id: str
    object: ObjectIn
    bytes: int
    expires_at: float


class ObjectStore:
    """tenant → {object id → object}, bounded per tenant (see module doc)."""

    def __init__(self, ttl_s: float, max_objects: int, max_bytes: int) -> None:
        self.ttl_s = ttl_s
        self.max_objects = max_objects
        self.max_bytes = max_bytes
        self._tenants: dict[str, OrderedDict[str, StoredObject]] = {}

    def _live(self, tenant: str) -> OrderedDict[str, StoredObject]:
        objects = self._tenants.setdefault(tenant, OrderedDict())
        now = time.time()
        for object_id in [k for k, v in objects.items() if v.expires_at <= now]:
            del objects[object_id]
        return objects

    def put(self, tenant: str, obj: ObjectIn) -> StoredObject:
        """Store ``obj`` for ``tenant``; its entry (with a fresh id).

        Raises:
            Conflict: the tenant holds ``max_objects`` objects, or the object would exceed ``max_bytes``.
        """
        objects = self._live(tenant)
        size = object_bytes(obj)
        if len(objects) >= self.max_objects:
            raise Conflict(
                f"object: {len(objects)} objects stored, at most {self.max_objects} per key (MANI_MAX_OBJECTS);"
                " delete one or wait for one to expire",
                detail=[FieldError(field="object", problem=f"at most {self.max_objects} objects per key")],
            )
        held = sum(o.bytes for o in objects.values())
        if held + size > self.max_bytes:
            raise Conflict(
                f"object: {size} bytes would make {held + size} stored, at most {self.max_bytes} per key"
                " (MANI_MAX_OBJECT_STORE_BYTES)",
                detail=[FieldError(field="object", problem=f"more than {self.max_bytes} bytes stored per key")],
            )
        stored = StoredObject("obj_" + secrets.token_hex(8), obj, size, time.time() + self.ttl_s)
        objects[stored.id] = stored
        return stored

    def get(self, tenant: str, object_id: str) -> ObjectIn:
        """The object (its time to live starts again).

        Raises:
            NotFound: no such object for this tenant (never uploaded, expired, deleted, or another tenant's).
        """
        stored = self._live(tenant).get(object_id)
        if stored is None:
            raise NotFound(
                f"object_id: no object {object_id!r} (upload it with upload_object; objects expire "
                f"{self.ttl_s:g} s after their last use)",
                detail=[FieldError(field="object_id", problem="unknown or expired object")],
            )
        stored.expires_at = time.time() + self.ttl_s
        return stored.object

    def delete(self, tenant: str, object_id: str) -> bool:
        """Remove an object; whether there was one."""
        return self._live(tenant).pop(object_id, None) is not None

    def list(self, tenant: str) -> list[StoredObject]:
        """The tenant's live objects, oldest first."""
        return list(self._live(tenant).values())
