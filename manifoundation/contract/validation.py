"""Turn pydantic validation errors into the contract's `FieldError` list (one convention for every edge).

Field validators carry their location in pydantic's ``loc``; cross-field (model) validators name the field at
the start of their message, ``"normals: zero-length normal at index 3"``; both end up as
``FieldError(field="object.normals", problem="zero-length normal at index 3")``.
"""

from __future__ import annotations

import re

from pydantic import ValidationError

from manifoundation.contract.errors import FieldError
from manifoundation.contract.tasks import TASK_KINDS

_FIELD_PREFIX = re.compile(r"^(?P<field>[A-Za-z_][\w.]*): (?P<problem>.+)$", re.DOTALL)
_PYDANTIC_PREFIXES = ("Value error, ", "Assertion failed, ")
# A discriminated union adds the tag to the location (task.force_closure.…); it is not a field name.
_TASK_KINDS = frozenset(TASK_KINDS)


def field_errors(exc: ValidationError, root: str = "") -> list[FieldError]:
    """One `FieldError` per problem in ``exc``, with dotted field paths (list indices included).

    Args:
        exc: the pydantic error.
        root: a prefix for every path (e.g. ``"requests.3"`` when validating one item of a batch).
    """
    errors: list[FieldError] = []
    for err in exc.errors(include_url=False):
        loc = [str(p) for p in err["loc"]]
        parts = [p for i, p in enumerate(loc) if not (i > 0 and loc[i - 1] == "task" and p in _TASK_KINDS)]
        message = str(err["msg"])
        for prefix in _PYDANTIC_PREFIXES:
            message = message.removeprefix(prefix)
        match = _FIELD_PREFIX.match(message)
        if match and err["type"] == "value_error":
            leaf = match["field"]
            if not parts or parts[-1] != leaf.split(".")[0]:
                parts.append(leaf)
            message = match["problem"]
        path = ".".join([root, *parts] if root else parts) or "body"
        errors.append(FieldError(field=path, problem=message))
    return errors


def summary(errors: list[FieldError]) -> str:
    """A one-line message for an error body: the first problem and how many more."""
    if not errors:
        return "invalid input"
    first = f"{errors[0].field}: {errors[0].problem}"
    return first if len(errors) == 1 else f"{first} (and {len(errors) - 1} more)"
