"""The contract's version rule, and answers read leniently (a newer minor version may add answer fields)."""

from __future__ import annotations

import pydantic
import pytest

from manifoundation.contract import SCHEMA_VERSION, HealthPublic, JobPublic
from manifoundation.contract.common import ANSWER_CONTEXT
from manifoundation.contract.versions import CONTRACT_VERSION, Compatibility, compatibility, parse_version


@pytest.mark.parametrize(
    ("service", "client", "expected"),
    [
        ("1.0", "1.0", Compatibility.SAME),
        ("1.3", "1.2", Compatibility.NEWER_MINOR),
        ("1.2", "1.10", Compatibility.OLDER_MINOR),  # numbers, not text: 2 < 10
        ("2.0", "1.9", Compatibility.INCOMPATIBLE),
        ("0.9", "1.0", Compatibility.INCOMPATIBLE),
        ("v1", "1.0", Compatibility.INCOMPATIBLE),  # unreadable: nothing can be trusted
        ("", "1.0", Compatibility.INCOMPATIBLE),
    ],
)
def test_the_rule(service: str, client: str, expected: Compatibility) -> None:
    assert compatibility(service, client) is expected


def test_this_contracts_version_names_its_routes_major() -> None:
    major, _ = parse_version(CONTRACT_VERSION)
    assert f"v{major}" == SCHEMA_VERSION


def test_unknown_answer_fields_are_dropped_at_every_level_only_when_asked() -> None:
    job = {"id": "j1", "state": "queued", "created_at": 1.0, "added_later": 1,
           "progress": {"stage": "queued", "fraction": 0.0, "added_later_too": "x"}}  # fmt: skip
    with pytest.raises(pydantic.ValidationError, match="added_later"):
        JobPublic.model_validate(job)  # the service's way: an unknown field is an error
    read = JobPublic.model_validate(job, context=ANSWER_CONTEXT)
    assert read.id == "j1" and read.progress is not None and read.progress.fraction == 0.0
    health = HealthPublic.model_validate_json(
        '{"backend": "embedded", "version": "9.9.9", "contract_version": "1.7", "uptime_s": 3}', context=ANSWER_CONTEXT
    )
    assert health.contract_version == "1.7"
    with pytest.raises(pydantic.ValidationError):  # what the contract does know is still checked
        JobPublic.model_validate({**job, "state": "napping"}, context=ANSWER_CONTEXT)
