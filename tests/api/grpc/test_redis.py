"""The same RPCs in front of Redis Streams: the gRPC side uses the app's queue object, whichever backend it is."""

from __future__ import annotations

import grpc
import pytest

from manifoundation.contract.protos.v1 import manifoundation_pb2 as pb

from .conftest import HAND, Service, request, wait_terminal


def test_synthesize_watch_and_cancel_over_redis(redis_service: Service) -> None:
    svc = redis_service
    assert svc.app.state.services.queue.backend == "redis"
    assert svc.stub.Synthesize(request(), metadata=svc.auth(), timeout=30).hand == HAND
    created = svc.stub.SubmitJob(request(max_iterations=2), metadata=svc.auth())
    updates = list(svc.stub.WatchJob(pb.WatchJobRequest(id=created.id), metadata=svc.auth(), timeout=30))
    assert updates[-1].state == "succeeded" and updates[-1].result.hand == HAND
    long = svc.stub.SubmitJob(request(max_iterations=20), metadata=svc.auth())
    svc.stub.CancelJob(pb.JobRef(id=long.id), metadata=svc.auth())
    assert wait_terminal(svc, long.id).state == "cancelled"
    with pytest.raises(grpc.RpcError) as caught:
        svc.stub.GetJob(pb.GetJobRequest(id="nope"), metadata=svc.auth())
    assert caught.value.code() is grpc.StatusCode.NOT_FOUND
