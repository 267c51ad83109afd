"""Objects an agent uploaded once and names by id afterwards: per tenant, with a time to live and size limits.

An LLM agent should not paste a point cloud into every call: ``upload_object`` validates the object once with
the contract (`ObjectIn`) and answers an id; the other tools take that id. Each tenant (API key) has its own
namespace: another tenant's id is unknown to it, like an id that never existed. Limits
(`manifoundation.server.api.settings`):
``object_ttl_s`` after the last use, ``max_objects`` per tenant, ``max_object_store_bytes`` of arrays per tenant
(the least recently used objects are not evicted to make room: the upload is refused, naming the limit).

Per process: behind several replicas an object lives on the replica that took the upload (route an agent's
session to one replica, or upload again). An object over `manifoundation.server.spool.SPOOL_BYTES` is kept packed
in a spool directory of the store's own (removed by `close`), not in memory: a key's quota of 64 MiB of arrays,
times every key, would otherwise stay in the API process.
"""

from __future__ import annotations

import secrets
import time
from collections import OrderedDict
from dataclasses import dataclass
from typing import Any

import numpy as np

from manifoundation.contract import FieldError, ObjectIn
from manifoundation.contract.codec import MSGPACK, dump_model, unpack
from manifoundation.server.api.errors import Conflict, NotFound
from manifoundation.server.spool import (
    SPOOL_BYTES,
    new_spool,
    open_payload,
    read_payload,
    remove_payload,
    remove_spool,
    write_payload,
)


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
    """One uploaded object: in memory (``object``), or packed in the store's spool (``path``)."""

    id: str
    object: ObjectIn | None
    bytes: int
    expires_at: float
    path: str | None = None


class ObjectStore:
    """tenant → {object id → object}, bounded per tenant (see module doc)."""

    def __init__(self, ttl_s: float, max_objects: int, max_bytes: int) -> None:
        self.ttl_s = ttl_s
        self.max_objects = max_objects
        self.max_bytes = max_bytes
        self._tenants: dict[str, OrderedDict[str, StoredObject]] = {}
        self._spool: str | None = None

    def _live(self, tenant: str) -> OrderedDict[str, StoredObject]:
        objects = self._tenants.setdefault(tenant, OrderedDict())
        now = time.time()
        for object_id in [k for k, v in objects.items() if v.expires_at <= now]:
            _forget(objects.pop(object_id))
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
        if size > SPOOL_BYTES:
            if self._spool is None:
                self._spool = new_spool()
            stored.path = write_payload(self._spool, dump_model(obj, MSGPACK))
            stored.object = None
        objects[stored.id] = stored
        return stored

    def fields(self, tenant: str, object_id: str) -> dict[str, Any]:
        """The object as the contract's plain data (what a request's ``object`` is; its time to live starts again).

        Raises:
            NotFound: no such object for this tenant (never uploaded, expired, deleted, or another tenant's).
        """
        return _fields_of(self._found(tenant, object_id))

    def get(self, tenant: str, object_id: str) -> ObjectIn:
        """The object (its time to live starts again). Raises `NotFound` as `fields`."""
        stored = self._found(tenant, object_id)
        return stored.object if stored.object is not None else ObjectIn.model_validate(_fields_of(stored))

    def _found(self, tenant: str, object_id: str) -> StoredObject:
        stored = self._live(tenant).get(object_id)
        if stored is None:
            raise NotFound(
                f"object_id: no object {object_id!r} (upload it with upload_object; objects expire "
                f"{self.ttl_s:g} s after their last use)",
                detail=[FieldError(field="object_id", problem="unknown or expired object")],
            )
        stored.expires_at = time.time() + self.ttl_s
        return stored

    def delete(self, tenant: str, object_id: str) -> bool:
        """Remove an object; whether there was one."""
        stored = self._live(tenant).pop(object_id, None)
        if stored is not None:
            _forget(stored)
        return stored is not None

    def list(self, tenant: str) -> list[StoredObject]:
        """The tenant's live objects, oldest first."""
        return list(self._live(tenant).values())

    def close(self) -> None:
        """Forget every object and remove the spool."""
        self._tenants.clear()
        if self._spool is not None:
            remove_spool(self._spool)
            self._spool = None


def _fields_of(stored: StoredObject) -> dict[str, Any]:
    """A stored object as the contract's plain data: read back from the spool, or dumped from memory."""
    if stored.path is not None:
        data: dict[str, Any] = unpack(read_payload(open_payload(stored.path)))
        return data
    assert stored.object is not None
    return stored.object.model_dump(mode="python", exclude_none=True)


def _forget(stored: StoredObject) -> None:
    if stored.path is not None:
        remove_payload(stored.path)
