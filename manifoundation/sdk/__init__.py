"""The ManiFoundation Python SDK: contact synthesis from a planner or a robot program.

Quick start::

    from manifoundation.sdk import Client, delta_pose, object_from_file

    with Client("http://127.0.0.1:8000") as client:
        obj = object_from_file("examples/data/box.npz")
        result = client.synthesize(obj, delta_pose([0, 0, 0.05]), "leap", method="direct_grasp")
        print(result.best.palm_position, result.best.quality.success)

Public names:

- clients: `Client`, `AsyncClient` (same calls, awaited), `RetryPolicy`; handles `Job`, `AsyncJob`, `Batch`,
  `AsyncBatch`. Sync clients close with ``close()``, async ones with ``aclose()`` (or ``with`` / ``async with``).
- inputs: `object_from_points`, `object_from_mesh`, `object_from_file`, `save_object`, `delta_pose`,
  `target_points`, `force_closure`, `wrench`, `make_request`, `robot_registration`; hands: `hand_registration`
  (an archive, folder or URDF/MJCF file, cut at a ``palm``), `zip_folder`; plans (``client.plan``,
  ``client.submit_plan``): `make_plan`, `box_obstacle`, `as_pose`.
- outputs: `result_to_dict`, `result_to_json`, `load_result`, `result_figure`.
- errors: `ManiError` › `RequestError` › (`ValidationError`, `Unauthorized`, `NotFound`, `RateLimited`,
  `ServerError`); `Unreachable`; `TimeoutError`; `JobFailed` (`JobExpired`: also a `TimeoutError`);
  `IncompatibleService` (another major version of the contract); `MissingExtra` (an optional part not installed);
  `NeedsHttp` (a call only HTTP serves, made on a gRPC client); the warning `ContractWarning` (a newer minor
  version: docs/compatibility.md).
- gRPC: `GrpcClient` and its `GrpcJob` in ``manifoundation.sdk.grpc_client``, `AsyncGrpcClient` and its `AsyncGrpcJob`
  (the same calls, awaited) in ``manifoundation.sdk.grpc_async_client``: the same surface, results and errors over
  the service's gRPC port (one base, `manifoundation.sdk._api` / ``_async_api``, over each transport); the calls
  with no RPC (``jobs``, ``robot_preview``, ``delete_robot``, ``health``, ``ready``) raise `NeedsHttp`. They
  need the ``[grpc]`` extra, so they are imported from their modules, not from here (importing
  ``manifoundation.sdk`` never loads grpcio).

The wire models (`SynthesisRequest`, `SynthesisResult`, `JobPublic`, ...) live in `manifoundation.contract`. The SDK
never imports torch or server code.
"""

from manifoundation.sdk.async_client import AsyncBatch, AsyncClient, AsyncJob
from manifoundation.sdk.client import Batch, Client, Job
from manifoundation.sdk.errors import (
    ContractWarning,
    IncompatibleService,
    JobExpired,
    JobFailed,
    ManiError,
    MissingExtra,
    NeedsHttp,
    NotFound,
    RateLimited,
    RequestError,
    ServerError,
    TimeoutError,
    Unauthorized,
    Unreachable,
    ValidationError,
)
from manifoundation.sdk.hands import hand_registration, zip_folder
from manifoundation.sdk.objects import object_from_file, object_from_mesh, object_from_points, save_object
from manifoundation.sdk.outputs import load_result, result_figure, result_to_dict, result_to_json
from manifoundation.sdk.plans import as_pose, box_obstacle, make_plan
from manifoundation.sdk.requests import make_request, robot_registration
from manifoundation.sdk.retry import RetryPolicy
from manifoundation.sdk.tasks import delta_pose, force_closure, target_points, wrench

__all__ = [
    "AsyncBatch",
    "AsyncClient",
    "AsyncJob",
    "Batch",
    "Client",
    "ContractWarning",
    "IncompatibleService",
    "Job",
    "JobExpired",
    "JobFailed",
    "ManiError",
    "MissingExtra",
    "NeedsHttp",
    "NotFound",
    "RateLimited",
    "RequestError",
    "RetryPolicy",
    "ServerError",
    "TimeoutError",
    "Unauthorized",
    "Unreachable",
    "ValidationError",
    "as_pose",
    "box_obstacle",
    "delta_pose",
    "force_closure",
    "hand_registration",
    "load_result",
    "make_plan",
    "make_request",
    "object_from_file",
    "object_from_mesh",
    "object_from_points",
    "result_figure",
    "result_to_dict",
    "result_to_json",
    "robot_registration",
    "save_object",
    "target_points",
    "wrench",
    "zip_folder",
]
