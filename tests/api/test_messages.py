"""Error messages and documentation a client can act on (issue #16, item 10)."""

from __future__ import annotations

import numpy as np
from fastapi.testclient import TestClient

from manifoundation.contract.codec import MSGPACK
from manifoundation.server.api.app import create_app
from manifoundation.server.api.settings import Settings

from .fakes import FakeQueue
from .helpers import request_body


def client() -> TestClient:
    return TestClient(create_app(Settings(rate_limit_per_s=0), queue=FakeQueue()))


def test_allow_lists_every_method_of_the_path() -> None:
    with client() as http:
        answer = http.put("/v1/jobs/abc")
        assert answer.status_code == 405
        assert answer.headers["allow"] == "DELETE, GET"
        assert http.put("/v1/robots/x").headers["allow"] == "DELETE, GET"


def test_malformed_msgpack_says_why() -> None:
    with client() as http:
        answer = http.post("/v1/jobs", content=b"\xc1", headers={"Content-Type": MSGPACK})
        assert answer.status_code == 400
        error = answer.json()["error"]
        assert error.startswith("malformed msgpack body: ") and len(error) > len("malformed msgpack body: ")


def test_collinear_points_are_refused_in_plain_words() -> None:
    body = request_body()
    line = np.linspace(0, 0.1, 128)
    body["object"] = {"points": np.stack([line, line, line], axis=1).tolist()}
    with client() as http:
        answer = http.post("/v1/jobs", json=body)
        assert answer.status_code == 422 and "lie on one line" in answer.json()["error"], answer.text


def test_robot_messages_name_the_field_once_and_mention_ignored_meshes() -> None:
    from manifoundation.server.api.errors import from_exception
    from manifoundation.server.queue import RobotInvalid

    assert from_exception(RobotInvalid("urdf: malformed XML")).message == "urdf: malformed XML"
    assert from_exception(RobotInvalid("fingertips: unknown links ['x']")).detail[0].field == "fingertips"  # type: ignore[index]
    assert from_exception(RobotInvalid("no <robot> element")).message == "urdf: no <robot> element"
    urdf = '<robot name="r"><link name="a"><visual><geometry><mesh filename="package://h/a.stl"/></geometry>' \
           "</visual></link></robot>"  # fmt: skip
    with client() as http:
        answer = http.post("/v1/robots", json={"name": "meshy", "urdf": urdf, "fingertips": ["a"]})
        assert answer.status_code == 201, answer.text
        assert "package://h/a.stl" in answer.json()["warnings"][0]


def test_openapi_documents_the_point_minimum_and_the_task_kind() -> None:
    with client() as http:
        schemas = http.get("/openapi.json").json()["components"]["schemas"]
    assert schemas["ObjectIn"]["properties"]["points"]["minItems"] == 64
    assert "kind" in schemas["ForceClosureTask"]["required"]
