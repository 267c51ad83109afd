"""Uploaded objects: one namespace per tenant, a time to live renewed by use, refusals naming the limit."""

from __future__ import annotations

import os
import time

import numpy as np
import pytest

from manifoundation.contract import ObjectIn
from manifoundation.server.api.errors import Conflict, NotFound
from manifoundation.server.api.mcp.objects import ObjectStore, object_bytes
from manifoundation.server.api.mcp.shapes import primitive
from manifoundation.server.spool import SPOOL_BYTES

BOX = primitive("box", [0.05, 0.05, 0.05], 128)


def test_a_tenant_sees_only_its_own_objects_and_deletes_them() -> None:
    store = ObjectStore(ttl_s=60, max_objects=4, max_bytes=10**6)
    mine = store.put("a", BOX)
    assert store.get("a", mine.id) is BOX
    assert mine.bytes == object_bytes(BOX) == 2 * BOX.points.nbytes + 8 * 3 * 8 + 12 * 3 * 8  # + 8 corners, 12 faces
    with pytest.raises(NotFound) as caught:
        store.get("b", mine.id)
    assert caught.value.detail and caught.value.detail[0].field == "object_id"
    assert store.delete("a", mine.id) and not store.delete("a", mine.id)
    with pytest.raises(NotFound):
        store.get("a", mine.id)


def test_objects_expire_after_their_last_use() -> None:
    store = ObjectStore(ttl_s=0.3, max_objects=4, max_bytes=10**6)
    kept, dropped = store.put("a", BOX), store.put("a", BOX)
    for _ in range(3):  # used every 0.15 s: it stays; the other one is not used and goes
        time.sleep(0.15)
        store.get("a", kept.id)
    assert [o.id for o in store.list("a")] == [kept.id]
    with pytest.raises(NotFound):
        store.get("a", dropped.id)


def test_count_and_byte_limits_refuse_the_upload() -> None:
    store = ObjectStore(ttl_s=60, max_objects=2, max_bytes=3 * object_bytes(BOX) - 1)
    store.put("a", BOX)
    store.put("a", BOX)
    with pytest.raises(Conflict, match="at most 2 per key"):
        store.put("a", BOX)
    store.put("b", BOX)  # another tenant's limits are its own
    small = ObjectStore(ttl_s=60, max_objects=10, max_bytes=object_bytes(BOX) + 1)
    small.put("a", BOX)
    with pytest.raises(Conflict, match="bytes"):
        small.put("a", BOX)


def test_a_large_object_waits_on_disk_and_comes_back_the_same() -> None:
    """An object over SPOOL_BYTES is kept packed in the store's spool, not in memory; it comes back as the same
    object (as plain data, what a request's ``object`` is, and validated); its file goes when it is deleted or
    expires, the spool when the store closes."""
    big = primitive("sphere", [0.04], 60_000)  # 2.9 MB of arrays
    store = ObjectStore(ttl_s=60, max_objects=4, max_bytes=10**8)
    kept, dropped, expiring = store.put("a", big), store.put("a", big), store.put("a", big)
    assert store.delete("a", dropped.id) and not os.path.exists(dropped.path or "")
    assert kept.object is None and kept.path is not None and os.path.getsize(kept.path) > SPOOL_BYTES
    again = ObjectIn.model_validate(store.fields("a", kept.id))
    assert np.array_equal(again.points, big.points) and np.array_equal(again.normals, big.normals)
    assert store.get("a", kept.id).model_dump(mode="json") == big.model_dump(mode="json")
    expiring.expires_at = time.time() - 1  # its time to live is over: the next look removes it and its file
    assert [o.id for o in store.list("a")] == [kept.id] and not os.path.exists(expiring.path or "")
    small = store.put("a", BOX)
    assert small.path is None and store.get("a", small.id) is BOX
    spool = os.path.dirname(kept.path)
    store.close()
    assert not os.path.exists(spool)
