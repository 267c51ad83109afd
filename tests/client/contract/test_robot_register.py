"""`RobotRegister`: exactly one source; an archive travels as bytes in msgpack and as base64 in JSON."""

from __future__ import annotations

import json

import pytest
from pydantic import ValidationError

from manifoundation.contract import MAX_ARCHIVE_BYTES, RobotRegister
from manifoundation.contract.codec import pack, unpack

ZIP = b"PK\x03\x04" + bytes(range(256))


def test_archive_round_trips_in_both_encodings() -> None:
    body = RobotRegister(name="g1", archive=ZIP, palm="right_hand_palm_link")
    as_json = json.loads(body.model_dump_json(exclude_none=True))
    assert isinstance(as_json["archive"], str)  # base64
    assert RobotRegister.model_validate(as_json).archive == ZIP
    as_msgpack = unpack(pack(body.model_dump(mode="python", exclude_none=True)))
    assert as_msgpack["archive"] == ZIP and RobotRegister.model_validate(as_msgpack).archive == ZIP
    assert body.stored_bytes == len(ZIP)


@pytest.mark.parametrize(
    ("fields", "words"),
    [
        ({}, "exactly one of 'archive', 'urdf' or 'mjcf'"),
        ({"archive": ZIP, "mjcf": "<mujoco/>"}, "exactly one"),
        ({"archive": "not base64!"}, "base64"),
        ({"mjcf": "<mujoco/>", "description": "a.xml"}, "description: only with an archive"),
        ({"archive": ZIP, "tip_offsets": [[0, 0, 0]]}, "tip_offsets"),
        ({"archive": b"x" * (MAX_ARCHIVE_BYTES + 1)}, "archive"),
    ],
)
def test_bad_registrations_name_the_field(fields: dict, words: str) -> None:
    with pytest.raises(ValidationError) as info:
        RobotRegister(name="h", **fields)
    assert words in str(info.value)


def test_the_description_limit_is_in_bytes_and_is_the_loaders() -> None:
    import pytest
    from pydantic import ValidationError

    from manifoundation.contract import MAX_URDF_BYTES, RobotRegister
    from manifoundation.core.robots.mjcf_archive import MAX_MJCF_BYTES
    from manifoundation.core.robots.urdf import MAX_URDF_BYTES as LOADER_LIMIT

    assert MAX_URDF_BYTES == LOADER_LIMIT == MAX_MJCF_BYTES
    wide = "<robot>" + "é" * (MAX_URDF_BYTES // 2) + "</robot>"  # fewer characters than the limit, more bytes
    assert len(wide) < MAX_URDF_BYTES < len(wide.encode())
    with pytest.raises(ValidationError, match="byte limit"):
        RobotRegister(name="wide_hand", urdf=wide, fingertips=["tip"])
