"""One translation of exceptions into job errors: typed science errors keep their type, pydantic errors name
fields, anything else is the service's fault (500), never a 4xx that blames the caller."""

from __future__ import annotations

import pydantic
import pytest

from manifoundation.contract import ErrorType, SynthesisRequest
from manifoundation.core.errors import Cancelled, HandLoadError, InvalidInput, ModelUnavailable, UnknownHand
from manifoundation.server.worker.pipeline import error_from_exception


@pytest.mark.parametrize(
    ("exc", "kind"),
    [
        (InvalidInput("object.points: too few"), ErrorType.VALIDATION_ERROR),
        (HandLoadError("urdf: no links"), ErrorType.ROBOT_INVALID),
        (UnknownHand("robot.name: unknown hand 'x'"), ErrorType.UNKNOWN_HAND),
        (ModelUnavailable("no model"), ErrorType.MODEL_UNAVAILABLE),
        (Cancelled("stop"), ErrorType.CANCELLED),
    ],
)
def test_science_errors_keep_their_contract_type(exc: Exception, kind: ErrorType) -> None:
    body = error_from_exception(exc)
    assert body.kind is kind and body.error == str(exc)


@pytest.mark.parametrize("exc", [ValueError("shapes (3,) and (4,) not aligned"), KeyError("x"), ZeroDivisionError()])
def test_untyped_exceptions_are_internal_errors(exc: Exception) -> None:
    body = error_from_exception(exc)
    assert body.kind is ErrorType.INTERNAL_ERROR and body.status == 500
    assert body.error.startswith(type(exc).__name__)


def test_a_payload_that_breaks_the_contract_names_the_field() -> None:
    with pytest.raises(pydantic.ValidationError) as info:
        SynthesisRequest.model_validate({"object": {"points": [[0, 0, 0]]}, "task": {"kind": "force_closure"}})
    body = error_from_exception(info.value)
    assert body.kind is ErrorType.VALIDATION_ERROR and body.detail
    assert any(d.field.startswith("object") for d in body.detail)
