"""JSON and msgpack bodies: round trips of whole requests and results, bounded decoding."""

from __future__ import annotations

import msgpack
import numpy as np
import pytest

from manifoundation.contract import SynthesisRequest, SynthesisResult
from manifoundation.contract.codec import JSON, MSGPACK, DecodeError, dump_model, load_model, media_type, pack, unpack


def _request(n: int = 128) -> SynthesisRequest:
    rng = np.random.default_rng(1)
    points = rng.normal(size=(n, 3))
    normals = points / np.linalg.norm(points, axis=1, keepdims=True)
    return SynthesisRequest.model_validate(
        {
            "object": {"points": points, "normals": normals, "region_mask": np.ones(n, dtype=bool)},
            "task": {"kind": "point_motion", "motion": np.full((n, 3), 0.01)},
            "robot": {"name": "leap"},
            "options": {"num_proposals": 2, "seed": 7},
        }
    )


def _result() -> SynthesisResult:
    return SynthesisResult.model_validate(
        {
            "hand": "leap",
            "model_version": "test",
            "heatmap": np.linspace(0, 1, 64),
            "proposals": [
                {
                    "contact_points": np.eye(3),
                    "contact_normals": -np.eye(3),
                    "forces": np.ones((3, 3)),
                    "fingertips": ["a", "b", "c"],
                    "palm_position": [0, 0, 0.1],
                    "palm_quaternion": [2, 0, 0, 0],
                    "joint_names": ["j0", "j1"],
                    "joint_values": [0.1, 0.2],
                    "quality": {
                        "success": True,
                        "converged": True,
                        "reason": "converged",
                        "iterations": 12,
                        "wrench_residual": 1e-8,
                        "max_tip_distance": 0.001,
                        "penetration_depth": 0.0,
                        "self_collision_depth": 0.0,
                    },
                }
            ],
            "timings": {"network": 0.01},
        }
    )


@pytest.mark.parametrize("content_type", [JSON, MSGPACK])
def test_request_round_trip(content_type: str) -> None:
    request = _request()
    again = load_model(SynthesisRequest, dump_model(request, content_type), content_type)
    np.testing.assert_array_equal(again.object.points, request.object.points)
    np.testing.assert_array_equal(again.task.motion, request.task.motion)  # type: ignore[union-attr]
    assert again.options == request.options
    assert again.model_dump(mode="json") == request.model_dump(mode="json")


@pytest.mark.parametrize("content_type", [JSON, MSGPACK])
def test_result_round_trip(content_type: str) -> None:
    result = _result()
    again = load_model(SynthesisResult, dump_model(result, content_type), content_type)
    assert again.model_dump(mode="json") == result.model_dump(mode="json")
    np.testing.assert_allclose(again.proposals[0].palm_quaternion, [1, 0, 0, 0])


def test_msgpack_is_compact_and_binary() -> None:
    request = _request(2048)
    assert len(dump_model(request, MSGPACK)) < 0.6 * len(dump_model(request, JSON))
    raw = msgpack.unpackb(dump_model(request, MSGPACK))
    assert raw["object"]["points"]["dtype"] == "float64"


def test_media_type_aliases() -> None:
    assert media_type("application/x-msgpack; charset=binary") == MSGPACK
    assert media_type(None) == JSON
    assert media_type("text/plain") == JSON


@pytest.mark.parametrize("data", [b"\xc1", b"\x92\x01", msgpack.packb({1: 2})])
def test_malformed_msgpack_raises_decode_error(data: bytes) -> None:
    with pytest.raises(DecodeError):
        unpack(data)


def test_oversized_body_is_refused() -> None:
    with pytest.raises(DecodeError, match="exceeds the limit"):
        unpack(pack({"a": b"x" * 1000}), max_bytes=100)


def test_ext_types_are_refused() -> None:
    with pytest.raises(DecodeError):
        unpack(msgpack.packb(msgpack.ExtType(1, b"payload")))
