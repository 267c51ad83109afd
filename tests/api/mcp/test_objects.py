"""Uploaded objects: one namespace per tenant, a time to live renewed by use, refusals naming the limit."""

from __future__ import annotations

import time

import pytest

from manifoundation.server.api.errors import Conflict, NotFound
from manifoundation.server.api.mcp.objects import ObjectStore, object_bytes
from manifoundation.server.api.mcp.shapes import primitive

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
