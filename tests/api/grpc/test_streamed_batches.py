"""``SubmitBatchStream``: a ``BatchCreate`` sent in pieces, against a real server (issue 62, item 3).

gRPC receives a unary message whole before the servicer sees it (10 × 57.6 MB `SubmitBatch` calls took the API to
1.2 GB); the pieces of a streamed batch are read only while a large-body slot is held and go one at a time to a
body process. The same answer as `SubmitBatch`, the same errors, its own limit.
"""

from __future__ import annotations

import time
from collections.abc import Iterator

import grpc
import pytest

from manifoundation.contract.protos.v1 import manifoundation_pb2 as pb
from manifoundation.sdk._grpc_core import PIECE_BYTES, message_pieces
from manifoundation.server.spool import payload_files

from .conftest import KEY, Service, calls_ok, request, wait_terminal

PIECE = PIECE_BYTES


def _pieces(message: pb.BatchCreate) -> Iterator[pb.MessagePiece]:
    return iter(message_pieces(message.SerializeToString()))


def _error(call: grpc.RpcError) -> tuple[grpc.StatusCode, str]:
    return call.code(), call.details()  # type: ignore[attr-defined]


def test_a_batch_in_pieces_is_the_batch(service: Service) -> None:
    big = request(n=50_000, max_iterations=1)
    batch = pb.BatchCreate(requests=[big, request(max_iterations=1)])
    assert batch.ByteSize() > 2 * PIECE  # three pieces or more
    before = calls_ok(service, "SubmitBatchStream")
    created = service.stub.SubmitBatchStream(_pieces(batch), metadata=service.auth(), timeout=60)
    assert created.total == 2 and len(created.items) == 2
    for item in created.items:
        assert wait_terminal(service, item.job_id, 60).state == "succeeded"
    assert calls_ok(service, "SubmitBatchStream") == before + 1
    assert payload_files(service.app.state.services.queue.spool) == []  # spooled by a body process, gone with the jobs


def test_the_errors_of_a_batch_in_pieces_are_submit_batchs(service: Service) -> None:
    big = request(n=50_000)
    broken = pb.BatchCreate(requests=[request(), big])
    broken.requests[1].object.normals.data = broken.requests[1].object.normals.data[:-1]
    with pytest.raises(grpc.RpcError) as streamed:
        service.stub.SubmitBatchStream(_pieces(broken), metadata=service.auth(), timeout=60)
    with pytest.raises(grpc.RpcError) as whole:
        service.stub.SubmitBatch(broken, metadata=service.auth(), timeout=60)
    assert _error(streamed.value) == _error(whole.value)
    code, details = _error(streamed.value)
    assert code is grpc.StatusCode.INVALID_ARGUMENT and "requests.1.object.normals" in details
    with pytest.raises(grpc.RpcError) as nothing:  # no piece: the empty BatchCreate, as SubmitBatch reads it
        service.stub.SubmitBatchStream(iter([]), metadata=service.auth(), timeout=30)
    assert nothing.value.code() is grpc.StatusCode.INVALID_ARGUMENT and "requests" in nothing.value.details()
    with pytest.raises(grpc.RpcError) as anonymous:
        service.stub.SubmitBatchStream(_pieces(pb.BatchCreate(requests=[request()])), timeout=30)
    assert anonymous.value.code() is grpc.StatusCode.UNAUTHENTICATED
    assert payload_files(service.app.state.services.queue.spool) == []  # a refused batch leaves no payload behind


def test_pieces_over_the_message_limit_are_refused(service: Service) -> None:
    services = service.app.state.services
    settings = services.settings
    services.settings = settings.model_copy(update={"grpc_max_message_bytes": 2 * PIECE})
    try:
        batch = pb.BatchCreate(requests=[request(n=100_000)])
        assert batch.ByteSize() > 2 * PIECE
        with pytest.raises(grpc.RpcError) as caught:
            service.stub.SubmitBatchStream(_pieces(batch), metadata=service.auth(KEY), timeout=60)
    finally:
        services.settings = settings
    code, details = _error(caught.value)
    assert code is grpc.StatusCode.RESOURCE_EXHAUSTED and "MANI_GRPC_MAX_MESSAGE_BYTES" in details


def test_a_sender_too_slow_between_pieces_lets_its_slot_go(service: Service) -> None:
    """As an HTTP body: a stream that stops sending for MANI_BODY_IDLE_TIMEOUT is ended (it holds a large-body
    slot meanwhile)."""
    services = service.app.state.services
    settings = services.settings
    services.settings = settings.model_copy(update={"body_idle_timeout": 0.5})
    pieces = list(_pieces(pb.BatchCreate(requests=[request(n=50_000)])))

    def stalling() -> Iterator[pb.MessagePiece]:
        yield pieces[0]
        time.sleep(3)
        yield from pieces[1:]

    started = time.monotonic()
    try:
        with pytest.raises(grpc.RpcError) as caught:
            service.stub.SubmitBatchStream(stalling(), metadata=service.auth(), timeout=30)
    finally:
        services.settings = settings
    code, details = _error(caught.value)
    assert code is grpc.StatusCode.DEADLINE_EXCEEDED and "no piece for 0.5 s" in details
    assert time.monotonic() - started < 3  # answered at the idle limit, not when the sender resumed
