"""The errors the science raises on purpose, each naming the contract's error type it stands for.

``code`` is the name of the wire contract's `ErrorType` member (the science cannot import the contract: it sits
below it; a test keeps the two in step). The worker core maps a `ScienceError` to that type; any other exception
out of the science is a fault of the service (``InternalError``), never blamed on the caller.

    ScienceError                  InternalError
    ├── InvalidInput              ValidationError   the input cannot be processed (the message names the field)
    │   ├── InvalidPointCloud     ValidationError   points/normals/mask malformed or too few for a surface
    │   ├── InvalidContacts       ValidationError   given contacts unusable (e.g. off the object): ``contacts.points``
    │   ├── HandLoadError         RobotInvalid      a robot description is malformed, unsafe or inconsistent
    │   └── PlanningError         ValidationError   (manifoundation.core.planning) a plan that cannot be planned; of it:
    │       ├── InfeasibleWaypoint  InfeasibleWaypoint  a start / waypoint in collision, not repaired
    │       └── NoPathFound         NoPathFound         no collision-free motion for a segment in time
    ├── UnknownHand               UnknownHand       no hand of that name
    ├── ModelUnavailable          ModelUnavailable  method "network" without a loaded model
    ├── CheckpointError           ModelUnavailable  a checkpoint is missing, malformed or mismatched
    └── Cancelled                 Cancelled         the caller's ``should_cancel()`` returned true
"""

from __future__ import annotations

from typing import ClassVar


class ScienceError(Exception):
    """Base of the science's deliberate errors."""

    code: ClassVar[str] = "InternalError"


class InvalidInput(ScienceError, ValueError):
    """An input that cannot be processed (the message starts with the field's name)."""

    code = "ValidationError"


class InvalidPointCloud(InvalidInput):
    """Points/normals/mask of the wrong shape, non-finite, or too few to define a surface."""


class InvalidContacts(InvalidInput):
    """Given contacts (method "contacts") that cannot be used, e.g. far from the object's surface."""

    field: ClassVar[str] = "contacts.points"  # the wire field the worker names in the error's detail


class HandLoadError(InvalidInput):
    """A robot description is malformed, unsafe or inconsistent (the message says which and where)."""

    code = "RobotInvalid"


class UnknownHand(ScienceError, LookupError):
    """No hand of that name (the message lists the names)."""

    code = "UnknownHand"


class ModelUnavailable(ScienceError, RuntimeError):
    """Method "network" without a predictor (no trained model loaded)."""

    code = "ModelUnavailable"


class CheckpointError(ModelUnavailable, ValueError):
    """A checkpoint is missing, malformed, or does not match the configuration."""


class Cancelled(ScienceError):
    """The caller's ``should_cancel()`` returned true."""

    code = "Cancelled"


def all_errors() -> list[type[ScienceError]]:
    """Every `ScienceError` class (for the test that keeps the codes in step with the contract)."""
    found: list[type[ScienceError]] = []
    pending: list[type[ScienceError]] = [ScienceError]
    while pending:
        cls = pending.pop()
        found.append(cls)
        pending.extend(cls.__subclasses__())
    return found
